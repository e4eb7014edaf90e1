//! Angles of interval vectors: a proven enclosure of arg(x, y), and the shift of an angle
//! interval by whole turns.

use super::trig::{cos, sin};
use super::{interval, point, Interval};

/// True when every vector of the box `[x]×[y]` has its angle strictly between `lo` and `hi`
/// (modulo 2π), for `hi − lo < π`.
///
/// Proven with the sound sine and cosine: every vector lies strictly counter-clockwise of
/// direction `lo` (`cos lo·y − sin lo·x > 0`) and strictly clockwise of direction `hi`. The
/// strict signs exclude the zero vector.
pub fn strictly_between(x: Interval, y: Interval, lo: f64, hi: f64) -> bool {
    let left = cos(point(lo)) * y - sin(point(lo)) * x;
    let right = cos(point(hi)) * y - sin(point(hi)) * x;
    hi - lo < 3.0 && left.inf() > 0.0 && right.sup() < 0.0
}

/// A sound enclosure of arg(x, y), within (−π, π] up to the enclosure's width, or `None`
/// when (x, y) may be 0 or the guess cannot be proven.
///
/// The guess is `f64::atan2` at the midpoint, widened by 1e-15, 1e-14, … up to 1e-3 until
/// `strictly_between` proves it: no bound on the library's atan2 error is assumed.
pub fn arg(x: Interval, y: Interval) -> Option<Interval> {
    let phi = y.mid().atan2(x.mid());
    let mut eps = 1e-15f64;
    while eps < 1e-2 {
        let (lo, hi) = (phi - eps, phi + eps);
        if strictly_between(x, y, lo, hi) {
            return Some(interval(lo, hi));
        }
        eps *= 10.0;
    }
    None
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

    #[test]
    fn arg_encloses_the_angle_of_every_vector_and_refuses_the_origin() {
        for k in 0..64 {
            let angle = -3.1 + 6.2 * f64::from(k) / 63.0;
            let (c, s) = (angle.cos(), angle.sin());
            let a = arg(interval(c, c), interval(s, s)).expect("a unit vector");
            assert!(a.contains(angle), "{angle} not in {a:?}");
            assert!(a.wid() <= 1e-12);
        }
        assert!(arg(interval(-1e-3, 1e-3), interval(-1e-3, 1e-3)).is_none());
        assert!(!strictly_between(interval(0.0, 0.0), interval(0.0, 0.0), -0.1, 0.1));
    }

    #[test]
    fn wrap_moves_the_midpoint_into_one_turn() {
        let w = wrap(interval(7.0, 7.5));
        assert!(w.contains(7.0 - std::f64::consts::TAU) && w.contains(7.5 - std::f64::consts::TAU));
        assert_eq!(wrap(interval(-1.0, 1.0)), interval(-1.0, 1.0));
    }
}

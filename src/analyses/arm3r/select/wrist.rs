//! Whether a wrist is spherical: the three-valued test of whether the axes of joints 4-6 meet
//! in one point (`wrist`: proven to meet within a tolerance, proven to miss every point, or
//! neither), in interval arithmetic on the stated geometry, and the nearest-point helper the
//! choice of a non-spherical wrist's point uses.

use crate::analyses::arm3r::chain::{cross, dot, sub, V3};
use crate::kernel::interval::point;
use nalgebra::Vector3;

/// What the axes of the three wrist joints (at the wrist's zero, which suffices: a common point
/// of the three lies on axes 4 and 5 and stays put as they turn) were proven to do.
pub(super) enum Wrist {
    /// They pass within `miss` metres (at most the tolerance) of `centre`.
    Spherical { centre: V3, miss: f64 },
    /// No point lies within this tolerance (metres) of all three.
    Apart(f64),
    /// Neither could be proven.
    Undecided,
}

/// The three-valued test of a spherical wrist on the stated geometry, in interval arithmetic.
/// `tolerance` gives the allowed miss about a candidate point.
///
/// Meeting: the point nearest the three lines (least squares, in floating point) is a guess;
/// the bound on its distance from each axis is what decides. Missing: for a pair of
/// non-parallel axes, every point within `t` of both has its foot on the first at a parameter
/// `s` where that foot is within `2t` of the second (a quadratic in `s`, solved in intervals);
/// the box of those points, widened by `t`, is then proven farther than `t` from the third axis.
/// Exactly parallel axes more than `2t` apart are apart outright.
pub(super) fn wrist(axes: &[(V3, V3); 3], tolerance: &dyn Fn(&V3) -> f64) -> Wrist {
    let mid = |v: &V3| Vector3::from(v.map(|x| x.mid()));
    let dist2 = |x: &V3, (o, u): &(V3, V3)| {
        let c = cross(&sub(x, o), u);
        dot(&c, &c) / dot(u, u)
    };
    // Least squares: sum over the axes of (I - u u^T) x = sum of (I - u u^T) o.
    let (mut a, mut rhs) = (nalgebra::Matrix3::zeros(), Vector3::zeros());
    for (o, u) in axes {
        let (o, u) = (mid(o), mid(u).normalize());
        let proj = nalgebra::Matrix3::identity() - u * u.transpose();
        a += proj;
        rhs += proj * o;
    }
    let mut fallback = f64::INFINITY;
    if let Some(x) = a.try_inverse().map(|inv| inv * rhs) {
        let centre: V3 = [x[0], x[1], x[2]].map(point);
        let miss = axes.iter().map(|l| dist2(&centre, l).sup().max(0.0).sqrt()).fold(0.0, f64::max);
        let t = tolerance(&centre);
        if miss <= t {
            return Wrist::Spherical { centre, miss };
        }
        fallback = t;
    }
    // The tolerance about any point that could be within it is the one about the guess (the
    // lever barely changes over such distances); without a guess, the length floor.
    let t = if fallback.is_finite() { fallback } else { tolerance(&axes[0].0) };
    let ti = point(t);
    for (i, j, k) in [(0, 1, 2), (1, 2, 0), (0, 2, 1)] {
        let ((oi, ui), (oj, uj), lk) = (&axes[i], &axes[j], &axes[k]);
        let b = cross(ui, uj);
        let bb = dot(&b, &b);
        let uu = dot(uj, uj);
        if b.iter().all(|x| x.inf() == 0.0 && x.sup() == 0.0) {
            // Exactly parallel: the distance of oi from axis j is their distance.
            if dist2(oi, &(*oj, *uj)).inf() > (point(2.0) * ti).sqr().sup() {
                return Wrist::Apart(t);
            }
            continue;
        }
        if bb.inf() <= 0.0 {
            continue;
        }
        // |a + s b|^2 / |uj|^2 <= 4 t^2, with a = (oi - oj) x uj.
        let av = cross(&sub(oi, oj), uj);
        let (ab, aa) = (dot(&av, &b), dot(&av, &av));
        let disc = ab.sqr() - bb * (aa - point(4.0) * ti.sqr() * uu);
        if disc.sup() < 0.0 {
            return Wrist::Apart(t);
        }
        let root = disc.sqrt();
        let (lo, hi) = (((-ab) - root) / bb, ((-ab) + root) / bb);
        let s = crate::kernel::interval::interval(lo.inf(), hi.sup());
        let widen = crate::kernel::interval::interval(-t, t);
        let region: V3 = [0, 1, 2].map(|c| oi[c] + s * ui[c] + widen);
        if dist2(&region, lk).inf() > ti.sqr().sup() {
            return Wrist::Apart(t);
        }
    }
    Wrist::Undecided
}

/// The point of the first line nearest the second (floating point); `None` when parallel.
pub(super) fn nearest_on_first(p: &[f64; 3], u: &[f64; 3], q: &[f64; 3], v: &[f64; 3]) -> Option<[f64; 3]> {
    let (p, u, q, v) = (Vector3::from(*p), Vector3::from(*u), Vector3::from(*q), Vector3::from(*v));
    let w = p - q;
    let (a, b, c, d, e) = (u.dot(&u), u.dot(&v), v.dot(&v), u.dot(&w), v.dot(&w));
    let den = a * c - b * b;
    (den.abs() > 1e-12 * a * c).then(|| {
        let x = p + u * ((b * e - c * d) / den);
        [x[0], x[1], x[2]]
    })
}

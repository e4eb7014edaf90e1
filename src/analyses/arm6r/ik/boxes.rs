//! Relations between the boxes of an answer: whether they meet (one solution may lie in two),
//! hulls, and the merging of boxes to search.

use crate::kernel::interval::Interval;

/// Whether two boxes to search meet.
fn meet(a: &[[f64; 2]; 6], b: &[[f64; 2]; 6]) -> bool {
    (0..6).all(|d| a[d][0] <= b[d][1] && b[d][0] <= a[d][1])
}

/// The boxes merged into the hulls of those that meet, until no two meet.
pub(super) fn merged(mut boxes: Vec<[[f64; 2]; 6]>) -> Vec<[[f64; 2]; 6]> {
    let mut out: Vec<[[f64; 2]; 6]> = Vec::new();
    while let Some(mut b) = boxes.pop() {
        while let Some(i) = out.iter().position(|o| meet(o, &b)) {
            let o = out.swap_remove(i);
            b = std::array::from_fn(|d| [b[d][0].min(o[d][0]), b[d][1].max(o[d][1])]);
        }
        out.push(b);
    }
    out
}

/// Whether two boxes share a point.
pub(super) fn meets(x: &[Interval; 6], y: &[Interval; 6]) -> bool {
    (0..6).all(|d| !x[d].disjoint(y[d]))
}

/// Whether some box of `x` meets some box of `y`: a sweep along the dimension in which `y`'s
/// boxes are narrowest against their spread (a cover's parameter, or a joint fixed along it),
/// so covers of thousands of boxes are checked against each other in about `(n + m) log m`.
pub(super) fn any_meet(x: &[[Interval; 6]], y: &[[Interval; 6]]) -> bool {
    if x.is_empty() || y.is_empty() {
        return false;
    }
    let widest = |d: usize| y.iter().map(|b| b[d].wid()).fold(0.0, f64::max);
    let all = hull(y);
    let narrowness = |d: usize| widest(d) / all[d].wid().max(f64::MIN_POSITIVE);
    let d = (0..6).min_by(|&i, &j| narrowness(i).total_cmp(&narrowness(j))).unwrap_or(0);
    let mut sorted: Vec<&[Interval; 6]> = y.iter().collect();
    sorted.sort_by(|a, b| a[d].inf().total_cmp(&b[d].inf()));
    // A box of `y` starting more than its width below `a` ends below it; twice the widest
    // width and a hair keep rounding in the subtraction from skipping one that meets.
    let reach = 2.0 * widest(d) + f64::MIN_POSITIVE;
    x.iter().any(|a| {
        let from = sorted.partition_point(|b| b[d].inf() < a[d].inf() - reach - a[d].inf().abs() * f64::EPSILON);
        sorted[from..].iter().take_while(|b| b[d].inf() <= a[d].sup()).any(|b| meets(a, b))
    })
}

/// The hull of boxes (not empty).
pub(super) fn hull(boxes: &[[Interval; 6]]) -> [Interval; 6] {
    boxes.iter().fold(boxes[0], |h, b| std::array::from_fn(|d| h[d].convex_hull(b[d])))
}

/// Whether two of the boxes overlap (then they may hold one solution).
pub(super) fn overlapping<'a>(boxes: impl Iterator<Item = &'a [Interval; 6]> + Clone) -> bool {
    boxes.clone().enumerate().any(|(i, x)| boxes.clone().take(i).any(|y| meets(x, y)))
}


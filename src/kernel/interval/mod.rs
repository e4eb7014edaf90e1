//! Interval boxes: the unit of work of every solver in the crate.
//!
//! Owns `IntervalBox` (a vector of `inari::Interval`, one per variable, plus the tree level at
//! which it was made), bisection, and the few set operations the driver needs.
//! It does no IO and knows nothing of equations.

pub(crate) mod angle;
pub(crate) mod fast;
mod graph;
pub mod trig;

pub(crate) use graph::BoxSweep;
pub use graph::{components_by, components_of_edges, flood_fill, labels, merge_touching, touching_pairs};

pub use inari::Interval;

/// `[lower, upper]`: an interval as the JSON reports write it.
pub type Bounds = [f64; 2];

/// `x` as `[lower, upper]`.
pub fn bounds(x: Interval) -> Bounds {
    [x.inf(), x.sup()]
}

/// The interval `[lo, hi]`, or `Interval::EMPTY` when `lo > hi` or either bound is NaN.
///
/// Bounds are taken as they are: callers that computed them in floating point must round
/// outward themselves (or build them with inari arithmetic).
pub fn interval(lo: f64, hi: f64) -> Interval {
    Interval::try_from((lo, hi)).unwrap_or(Interval::EMPTY)
}

/// The point interval `[x, x]` (empty for NaN or an infinite `x`).
pub fn point(x: f64) -> Interval {
    if x.is_finite() {
        interval(x, x)
    } else {
        Interval::EMPTY
    }
}

/// The strict sign of `x` when it excludes zero: `Some(true)` positive, `Some(false)` negative,
/// `None` when `x` may vanish (or is empty).
pub fn strict_sign(x: Interval) -> Option<bool> {
    if x.inf() > 0.0 {
        Some(true)
    } else if x.sup() < 0.0 {
        Some(false)
    } else {
        None
    }
}

/// A Cartesian product of intervals, one per variable of a system.
///
/// `level` is the depth in the branch-and-prune tree (0 for the initial box); it is kept for
/// diagnostics and convergence measurements.
#[derive(Clone, Debug, PartialEq)]
pub struct IntervalBox {
    /// One interval per variable, in the system's variable order.
    pub dims: Vec<Interval>,
    /// Depth in the search tree.
    pub level: u32,
}

impl IntervalBox {
    /// A box at level 0.
    pub fn new(dims: Vec<Interval>) -> Self {
        Self { dims, level: 0 }
    }

    /// Number of variables.
    pub fn len(&self) -> usize {
        self.dims.len()
    }

    /// True for a box over zero variables.
    pub fn is_empty(&self) -> bool {
        self.dims.is_empty()
    }

    /// True when any component is empty: the box holds no point.
    pub fn is_void(&self) -> bool {
        self.dims.iter().any(|d| d.is_empty())
    }

    /// Width of component `i`.
    pub fn width(&self, i: usize) -> f64 {
        self.dims[i].wid()
    }

    /// The widest component among `among`, with its width; `None` if `among` is empty.
    pub fn widest(&self, among: &[usize]) -> Option<(usize, f64)> {
        among
            .iter()
            .map(|&i| (i, self.dims[i].wid()))
            .fold(None, |best, (i, w)| match best {
                Some((_, bw)) if bw >= w => best,
                _ => Some((i, w)),
            })
    }

    /// Euclidean length of the diagonal over the components `among` (rounded up).
    pub fn diagonal(&self, among: &[usize]) -> f64 {
        let sum = among.iter().fold(point(0.0), |acc, &i| acc + point(self.dims[i].wid()).sqr());
        sum.sqrt().sup()
    }

    /// Splits component `i` at its midpoint into two boxes one level deeper; together they
    /// cover `self` (they share the midpoint).
    pub fn bisect(&self, i: usize) -> (IntervalBox, IntervalBox) {
        let d = self.dims[i];
        let m = d.mid();
        let mut lower = self.clone();
        let mut upper = self.clone();
        lower.dims[i] = interval(d.inf(), m);
        upper.dims[i] = interval(m, d.sup());
        lower.level += 1;
        upper.level += 1;
        (lower, upper)
    }

    /// True when `x` (one value per variable) lies in the box.
    pub fn contains(&self, x: &[f64]) -> bool {
        self.dims.len() == x.len() && self.dims.iter().zip(x).all(|(d, &v)| d.contains(v))
    }

    /// True when the two boxes share at least one point.
    pub fn intersects(&self, other: &IntervalBox) -> bool {
        self.dims.iter().zip(&other.dims).all(|(a, b)| !a.disjoint(*b))
    }

    /// The midpoint of every component.
    pub fn midpoint(&self) -> Vec<f64> {
        self.dims.iter().map(|d| d.mid()).collect()
    }
}

/// Labels each box with its connected component (boxes sharing a point are connected);
/// returns the labels and the number of components, numbered in order of first appearance.
///
/// Sort and sweep (`touching_pairs`), so that reporting a run of a million boxes stays cheap (an
/// all-pairs comparison takes minutes on a run stopped by its `--timeout`).
pub fn components(boxes: &[IntervalBox]) -> (Vec<usize>, usize) {
    let (labels, n, _) = components_counted(boxes);
    (labels, n)
}

/// `components`, also returning how many box pairs were compared in full (the sweep's work):
/// for tests that check the cost without timing it.
pub fn components_counted(boxes: &[IntervalBox]) -> (Vec<usize>, usize, u64) {
    graph::box_components(boxes)
}

/// The all-pairs definition of `components`, O(n²): the reference the tests hold the sweep to.
#[cfg(test)]
fn components_all_pairs(boxes: &[IntervalBox]) -> (Vec<usize>, usize) {
    components_by(boxes.len(), |i, j| boxes[i].intersects(&boxes[j]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn bisection_covers_parent_and_goes_one_level_deeper() {
        let b = IntervalBox::new(vec![interval(-1.0, 1.0), interval(2.0, 6.0)]);
        let (lo, hi) = b.bisect(1);
        assert_eq!(lo.dims[1], interval(2.0, 4.0));
        assert_eq!(hi.dims[1], interval(4.0, 6.0));
        assert_eq!((lo.level, hi.level), (1, 1));
        assert_eq!(b.widest(&[0, 1]), Some((1, 4.0)));
    }

    #[test]
    fn invalid_bounds_give_empty_intervals() {
        assert!(interval(1.0, 0.0).is_empty());
        assert!(interval(f64::NAN, 0.0).is_empty());
        assert!(point(f64::INFINITY).is_empty());
        assert!(IntervalBox::new(vec![interval(0.0, 1.0), Interval::EMPTY]).is_void());
    }

    proptest! {
        #[test]
        fn halves_cover_every_point(lo in -10.0f64..10.0, w in 0.0f64..5.0, t in 0.0f64..=1.0) {
            let b = IntervalBox::new(vec![interval(lo, lo + w)]);
            let x = lo + t * w;
            let (a, c) = b.bisect(0);
            prop_assert!(!b.contains(&[x]) || a.contains(&[x]) || c.contains(&[x]));
        }
    }

    /// Random boxes on a coarse integer grid, so that touching corners, shared faces and
    /// exact overlaps are common, with a void box now and then.
    fn grid_boxes(dims: usize) -> impl Strategy<Value = Vec<IntervalBox>> {
        let side = (0i32..12, 0i32..4, any::<bool>()).prop_map(|(lo, w, void)| if void && w == 3 { Interval::EMPTY } else { interval(f64::from(lo), f64::from(lo + w)) });
        prop::collection::vec(prop::collection::vec(side, dims), 0..60).prop_map(|v| v.into_iter().map(IntervalBox::new).collect())
    }

    proptest! {
        #[test]
        fn sweep_components_equal_all_pairs(boxes in (1usize..4).prop_flat_map(grid_boxes)) {
            prop_assert_eq!(components(&boxes), components_all_pairs(&boxes));
        }
    }

    #[test]
    fn sweep_compares_a_linear_number_of_pairs_along_a_curve() {
        // 200 000 boxes of width 1e-5 along the unit circle in (cos, sin): the shape of a
        // solution curve at fine sigma. All pairs would be 2e10 comparisons; the sweep along
        // the better coordinate compares each box with its few neighbours, plus the pile-ups
        // where the curve turns (O(√n) boxes each, so O(n) pairs).
        let n = 200_000usize;
        let w = 1e-5;
        let boxes: Vec<IntervalBox> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                let (s, c) = t.sin_cos();
                // Wide enough to reach the next box: one closed curve.
                let r = 0.5 * w + std::f64::consts::TAU / n as f64;
                IntervalBox::new(vec![interval(c - r, c + r), interval(s - r, s + r)])
            })
            .collect();
        let (_, clusters, compared) = components_counted(&boxes);
        assert_eq!(clusters, 1);
        assert!(compared <= 20 * n as u64, "{compared} comparisons for {n} boxes");
        // Cut the curve in two (five boxes out at two places: neighbours two apart still
        // overlap): two components.
        let cut: Vec<IntervalBox> = boxes.iter().enumerate().filter(|(k, _)| !(8..=12).contains(k) && !(n / 2 - 2..=n / 2 + 2).contains(k)).map(|(_, b)| b.clone()).collect();
        assert_eq!(components(&cut).1, 2);
    }

    #[test]
    fn boxes_over_no_variable_are_one_component_and_void_boxes_their_own() {
        let none = vec![IntervalBox::new(vec![]); 3];
        assert_eq!(components(&none), components_all_pairs(&none));
        let void = vec![IntervalBox::new(vec![Interval::EMPTY]), IntervalBox::new(vec![interval(0.0, 1.0)]), IntervalBox::new(vec![Interval::EMPTY])];
        assert_eq!(components(&void), (vec![0, 1, 2], 3));
    }

    #[test]
    fn touching_boxes_form_one_component() {
        use crate::kernel::interval::interval;
        let b = |lo: f64, hi: f64| IntervalBox::new(vec![interval(lo, hi)]);
        let (labels, n) = components(&[b(0.0, 1.0), b(3.0, 4.0), b(1.0, 2.0)]);
        assert_eq!(n, 2);
        assert_eq!(labels[0], labels[2]);
        assert_ne!(labels[0], labels[1]);
    }
}

//! Connected components: of box sets (boxes sharing a point), of grid cells, of any graph given
//! by its neighbours, its edges or a symmetric "touches" test, and parts merged while their hulls
//! touch. One flood fill does the labelling
//! for all of them, so every caller numbers components the same way: by their smallest vertex
//! (order of first appearance), each component's vertices listed in the order the fill reaches
//! them.

use super::{Interval, IntervalBox};

/// The connected components of the graph on the vertices `0..n` for which `keep` holds, with
/// the edges `neighbours(v, out)` pushes onto `out` (neighbours that are not kept are ignored).
///
/// Depth-first flood fill from each kept vertex not yet reached, in increasing order: component
/// `k` is the one holding the `k`-th smallest such start. Each component lists its vertices in
/// the order they are taken off the stack (its start first; the neighbours of a vertex are
/// pushed in the order given, so the last one is visited next). Callers that pick a
/// representative member rely on that order.
pub fn flood_fill(n: usize, keep: impl Fn(usize) -> bool, mut neighbours: impl FnMut(usize, &mut Vec<usize>)) -> Vec<Vec<usize>> {
    let mut reached = vec![false; n];
    let mut groups = Vec::new();
    let mut stack = Vec::new();
    let mut next = Vec::new();
    for start in 0..n {
        if reached[start] || !keep(start) {
            continue;
        }
        reached[start] = true;
        stack.push(start);
        let mut members = Vec::new();
        while let Some(v) = stack.pop() {
            members.push(v);
            next.clear();
            neighbours(v, &mut next);
            for &w in &next {
                if !reached[w] && keep(w) {
                    reached[w] = true;
                    stack.push(w);
                }
            }
        }
        groups.push(members);
    }
    groups
}

/// The component of each of `n` vertices from `flood_fill`'s groups (`usize::MAX` for a vertex
/// left out), and the number of components.
pub fn labels(n: usize, groups: &[Vec<usize>]) -> (Vec<usize>, usize) {
    let mut labels = vec![usize::MAX; n];
    for (k, g) in groups.iter().enumerate() {
        for &v in g {
            labels[v] = k;
        }
    }
    (labels, groups.len())
}

/// The components of `0..n` under a symmetric test `touches(i, j)`, all pairs compared:
/// labels numbered in order of first appearance, and their number. For small sets; box sets
/// use the sweep of `components`.
pub fn components_by(n: usize, touches: impl Fn(usize, usize) -> bool) -> (Vec<usize>, usize) {
    let groups = flood_fill(n, |_| true, |i, out| out.extend((0..n).filter(|&j| j != i && touches(i, j))));
    labels(n, &groups)
}

/// The components of `0..n` joined by the undirected `edges` (as `flood_fill`, every vertex kept).
pub fn components_of_edges(n: usize, edges: impl IntoIterator<Item = (usize, usize)>) -> Vec<Vec<usize>> {
    // Adjacency in compressed rows: one offset per vertex into one list of neighbours.
    let edges: Vec<(usize, usize)> = edges.into_iter().collect();
    let mut start = vec![0usize; n + 1];
    for &(a, b) in &edges {
        start[a + 1] += 1;
        start[b + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut adjacent = vec![0usize; 2 * edges.len()];
    for &(a, b) in &edges {
        adjacent[fill[a]] = b;
        fill[a] += 1;
        adjacent[fill[b]] = a;
        fill[b] += 1;
    }
    flood_fill(n, |_| true, |v, out| out.extend_from_slice(&adjacent[start[v]..start[v + 1]]))
}

/// Parts of `0..hulls.len()` merged until no two touch, each with its hull; `join(a, b)` is the
/// hull of `a` and `b` when they touch, `None` when they do not. Parts are listed by their
/// smallest member.
///
/// Unlike the components of the items' own contacts, two parts merge when their hulls touch,
/// though no member of one touches a member of the other. Each round joins the components of
/// the current parts under `join` (`flood_fill`) and ends when a round joins nothing. Every
/// merge is forced (hulls only grow, so parts that touch keep touching), so the parts are the
/// finest ones whose hulls are pairwise apart, whatever the order of merges. `join` must be
/// symmetric in whether it touches; it may return `b` reoriented (pairs of boxes taken in
/// either order).
pub fn merge_touching<H: Clone>(hulls: &[H], join: impl Fn(&H, &H) -> Option<H>) -> Vec<(H, Vec<usize>)> {
    let mut parts: Vec<(H, Vec<usize>)> = hulls.iter().cloned().enumerate().map(|(i, h)| (h, vec![i])).collect();
    loop {
        let n = parts.len();
        let groups = flood_fill(n, |_| true, |v, out| out.extend((0..n).filter(|&w| w != v && join(&parts[v].0, &parts[w].0).is_some())));
        if groups.len() == n {
            return parts;
        }
        parts = groups
            .into_iter()
            .map(|group| {
                let (mut hull, mut members) = parts[group[0]].clone();
                // In fill order each part touches one taken before it, hence the hull so far.
                for &v in &group[1..] {
                    hull = join(&hull, &parts[v].0).expect("invariant: a part met in the fill touches the hull of those before it");
                    members.extend_from_slice(&parts[v].1);
                }
                (hull, members)
            })
            .collect();
    }
}

/// The pairs `(i, j)`, `i ≠ j`, of the `live` boxes that share a point, boxes given by their
/// sides `side(i, d)` over `dims` coordinates; and how many pairs were compared in full.
///
/// Sort and sweep: the boxes are swept along the one coordinate on which the fewest pairs
/// overlap (counted exactly in O(n log n) per coordinate): only pairs that overlap there are
/// compared in full, and every pair that shares a point overlaps on every coordinate, so the
/// pairs are exactly the all-pairs ones. Along a curve of boxes a coordinate overlaps O(n)
/// pairs, so the whole is O(n log n) in practice.
pub fn touching_pairs(live: &[usize], dims: usize, side: impl Fn(usize, usize) -> Interval) -> (Vec<(usize, usize)>, u64) {
    let mut pairs = Vec::new();
    let compared = sweep(live, dims, side, |_, _| false, |i, j| pairs.push((i, j)));
    (pairs, compared)
}

/// The sweep of `touching_pairs`: `touch(i, j)` for each pair that shares a point, except the
/// pairs `skip` rules out before their full comparison; returns how many were compared in full.
fn sweep(live: &[usize], dims: usize, side: impl Fn(usize, usize) -> Interval, skip: impl FnMut(usize, usize) -> bool, touch: impl FnMut(usize, usize)) -> u64 {
    if dims == 0 || live.len() < 2 {
        return 0;
    }
    let (d, order) = sweep_order(live, dims, &side);
    sweep_slice(&order, 0..order.len(), d, dims, &side, skip, touch)
}

/// The coordinate to sweep along, the one on which the fewest pairs overlap, and the `live`
/// boxes in order of their lower bound on it.
fn sweep_order(live: &[usize], dims: usize, side: &impl Fn(usize, usize) -> Interval) -> (usize, Vec<usize>) {
    let by_inf = |d: usize| {
        let mut order = live.to_vec();
        order.sort_by(|&a, &b| side(a, d).inf().total_cmp(&side(b, d).inf()));
        order
    };
    // Pairs overlapping on coordinate d: for each box in order of lower bound, the later
    // boxes whose lower bound is at most its upper bound (closed intervals touch).
    let overlapping = |order: &[usize], d: usize| -> u128 {
        let infs: Vec<f64> = order.iter().map(|&i| side(i, d).inf()).collect();
        order
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let sup = side(i, d).sup();
                (infs.partition_point(|&x| x <= sup) - (k + 1)) as u128
            })
            .sum()
    };
    (0..dims)
        .map(|d| {
            let order = by_inf(d);
            (overlapping(&order, d), d, order)
        })
        .min_by_key(|(pairs, d, _)| (*pairs, *d))
        .map(|(_, d, order)| (d, order))
        .expect("invariant: dims > 0")
}

/// The sweep from the boxes at positions `from` of `order` (sorted along coordinate `d`): each
/// compared with the later ones that overlap it there.
fn sweep_slice(order: &[usize], from: std::ops::Range<usize>, d: usize, dims: usize, side: &impl Fn(usize, usize) -> Interval, mut skip: impl FnMut(usize, usize) -> bool, mut touch: impl FnMut(usize, usize)) -> u64 {
    let mut compared = 0u64;
    for k in from {
        let i = order[k];
        let sup = side(i, d).sup();
        for &j in &order[k + 1..] {
            if side(j, d).inf() > sup {
                break;
            }
            if skip(i, j) {
                continue;
            }
            compared += 1;
            if (0..dims).all(|e| !side(i, e).disjoint(side(j, e))) {
                touch(i, j);
            }
        }
    }
    compared
}

/// Which vertices are joined so far (union–find with path halving).
struct Joined(Vec<usize>);

impl Joined {
    fn new(n: usize) -> Self {
        Joined((0..n).collect())
    }

    fn root(&mut self, mut v: usize) -> usize {
        while self.0[v] != v {
            self.0[v] = self.0[self.0[v]];
            v = self.0[v];
        }
        v
    }

    fn same(&mut self, a: usize, b: usize) -> bool {
        self.root(a) == self.root(b)
    }

    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        self.0[ra] = rb;
    }
}

/// `components` with the number of box pairs compared in full (see `super::components_counted`).
pub(super) fn box_components(boxes: &[IntervalBox]) -> (Vec<usize>, usize, u64) {
    let sweep = BoxSweep::new(boxes);
    let (pairs, compared) = sweep.slice(0, 1);
    let (labels, count) = sweep.components([pairs]);
    (labels, count, compared)
}

/// The sweep that labels the components of a box set, cut into slices that threads or
/// processes can run apart: the components are those of every slice's pairs together.
///
/// Each slice sweeps a contiguous run of the sweep order against everything after it, with a
/// union–find of its own: a pair it has already joined through others adds nothing to the
/// components, and skipping it keeps many mutually overlapping boxes (a limit's undecided boxes
/// of a large system) from costing n² full comparisons of thousands of coordinates. Whatever
/// the slices, the labels are the same (a component's label is its smallest member's rank).
pub(crate) struct BoxSweep<'a> {
    boxes: &'a [IntervalBox],
    live: Vec<usize>,
    dims: usize,
    axis: usize,
    order: Vec<usize>,
}

impl<'a> BoxSweep<'a> {
    /// The sweep of `boxes`, its axis chosen and its order sorted.
    pub(crate) fn new(boxes: &'a [IntervalBox]) -> Self {
        // A void box shares no point with anything: it is its own component.
        let live: Vec<usize> = (0..boxes.len()).filter(|&i| !boxes[i].is_void()).collect();
        let dims = live.first().map_or(0, |&i| boxes[i].len());
        let (axis, order) = if dims == 0 || live.len() < 2 { (0, live.clone()) } else { sweep_order(&live, dims, &|i, d| boxes[i].dims[d]) };
        BoxSweep { boxes, live, dims, axis, order }
    }

    /// The joining pairs found by slice `part` of `parts`, and the pairs compared in full.
    pub(crate) fn slice(&self, part: usize, parts: usize) -> (Vec<(usize, usize)>, u64) {
        let n = self.order.len();
        let from = part * n / parts..(part + 1) * n / parts;
        let mut pairs = Vec::new();
        if self.dims == 0 {
            // Boxes over no variable are all the one point of a zero-dimensional space.
            pairs.extend(self.live[from.start..from.end.min(n.saturating_sub(1))].iter().map(|&i| (i, self.live[self.live.len() - 1])));
            return (pairs, 0);
        }
        let boxes = self.boxes;
        let joined = std::cell::RefCell::new(Joined::new(boxes.len()));
        let compared = sweep_slice(&self.order, from, self.axis, self.dims, &|i, d| boxes[i].dims[d], |i, j| joined.borrow_mut().same(i, j), |i, j| {
            joined.borrow_mut().join(i, j);
            pairs.push((i, j));
        });
        (pairs, compared)
    }

    /// Each box's component from every slice's pairs (`usize::MAX` for none), and their number.
    pub(crate) fn components(&self, pairs: impl IntoIterator<Item = Vec<(usize, usize)>>) -> (Vec<usize>, usize) {
        let n = self.boxes.len();
        labels(n, &components_of_edges(n, pairs.into_iter().flatten()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn flood_fill_numbers_by_first_vertex_and_lists_in_visit_order() {
        // A path 0 - 3 - 1, a lone 2, and 4 left out (though joined to 2).
        let edges: [&[usize]; 5] = [&[3], &[3], &[4], &[0, 1], &[2]];
        let groups = flood_fill(5, |v| v != 4, |v, out| out.extend_from_slice(edges[v]));
        assert_eq!(groups, vec![vec![0, 3, 1], vec![2]]);
        assert_eq!(labels(5, &groups), (vec![0, 0, 1, 0, usize::MAX], 2));
        // Neighbours pushed in order: the last one is visited first.
        let star = flood_fill(4, |_| true, |v, out| if v == 0 { out.extend([1, 2, 3]) });
        assert_eq!(star, vec![vec![0, 3, 2, 1]]);
    }

    /// Vertices, edges, expected labels, expected count.
    type Case<'a> = (usize, &'a [(usize, usize)], &'a [usize], usize);

    #[test]
    fn components_by_a_test_and_by_edges_agree_on_a_table() {
        let cases: [Case; 4] = [
            (0, &[], &[], 0),
            (3, &[], &[0, 1, 2], 3),
            (5, &[(4, 1), (2, 0)], &[0, 1, 0, 2, 1], 3),
            (6, &[(5, 0), (1, 3), (3, 5)], &[0, 0, 1, 0, 2, 0], 3),
        ];
        for (n, edges, want, count) in cases {
            let touches = |i: usize, j: usize| edges.iter().any(|&(a, b)| (a, b) == (i, j) || (b, a) == (i, j));
            assert_eq!(components_by(n, touches), (want.to_vec(), count));
            assert_eq!(labels(n, &components_of_edges(n, edges.iter().copied())), (want.to_vec(), count));
        }
    }

    /// Hull of two 2-D boxes when they share a point.
    fn join2(a: &[Interval; 2], b: &[Interval; 2]) -> Option<[Interval; 2]> {
        (0..2).all(|d| !a[d].disjoint(b[d])).then(|| [a[0].convex_hull(b[0]), a[1].convex_hull(b[1])])
    }

    #[test]
    fn merge_touching_joins_parts_whose_hulls_touch() {
        let iv = crate::kernel::interval::interval;
        // 0 and 1 touch; their hull reaches 2, which touches neither; 3 stays apart.
        let boxes = [[iv(0.0, 1.0), iv(0.0, 1.0)], [iv(1.0, 3.0), iv(1.0, 3.0)], [iv(2.5, 3.0), iv(0.0, 0.5)], [iv(5.0, 6.0), iv(5.0, 6.0)]];
        let parts = merge_touching(&boxes, join2);
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0].0, [iv(0.0, 3.0), iv(0.0, 3.0)]);
        let mut members = parts[0].1.clone();
        members.sort_unstable();
        assert_eq!(members, vec![0, 1, 2]);
        assert_eq!(parts[1], (boxes[3], vec![3]));
    }

    proptest! {
        #[test]
        fn components_by_a_test_equal_union_find(n in 0usize..30, edges in prop::collection::vec((0usize..30, 0usize..30), 0..40)) {
            let edges: Vec<(usize, usize)> = edges.into_iter().filter(|&(a, b)| a < n && b < n).collect();
            // Reference: repeated relabelling until every edge joins equal labels, then
            // renumbering by first appearance.
            let mut root: Vec<usize> = (0..n).collect();
            loop {
                let mut changed = false;
                for &(a, b) in &edges {
                    let m = root[a].min(root[b]);
                    if root[a] != m || root[b] != m {
                        let (ra, rb) = (root[a], root[b]);
                        for r in root.iter_mut() {
                            if *r == ra || *r == rb {
                                *r = m;
                            }
                        }
                        changed = true;
                    }
                }
                if !changed {
                    break;
                }
            }
            let mut ids = std::collections::HashMap::new();
            let want: Vec<usize> = root.iter().map(|r| { let next = ids.len(); *ids.entry(*r).or_insert(next) }).collect();
            let touches = |i: usize, j: usize| edges.iter().any(|&(a, b)| (a, b) == (i, j) || (b, a) == (i, j));
            prop_assert_eq!(components_by(n, touches), (want.clone(), ids.len()));
            prop_assert_eq!(labels(n, &components_of_edges(n, edges.iter().copied())), (want, ids.len()));
        }

        #[test]
        fn merge_touching_equals_merging_one_box_at_a_time(corners in prop::collection::vec((0u8..40, 0u8..40, 0u8..4, 0u8..4), 0..40)) {
            let iv = crate::kernel::interval::interval;
            let boxes: Vec<[Interval; 2]> = corners.iter().map(|&(x, y, w, h)| [iv(f64::from(x), f64::from(x + w)), iv(f64::from(y), f64::from(y + h))]).collect();
            // Reference: each box in turn absorbs every cluster its growing hull touches.
            let mut want: Vec<([Interval; 2], Vec<usize>)> = Vec::new();
            for (i, b) in boxes.iter().enumerate() {
                let (mut hull, mut members) = (*b, vec![i]);
                let mut k = 0;
                while k < want.len() {
                    if let Some(h) = join2(&hull, &want[k].0) {
                        hull = h;
                        members.extend(want.remove(k).1);
                        k = 0;
                    } else {
                        k += 1;
                    }
                }
                want.push((hull, members));
            }
            let sorted = |mut parts: Vec<([Interval; 2], Vec<usize>)>| {
                for p in &mut parts {
                    p.1.sort_unstable();
                }
                parts.sort_by_key(|p| p.1[0]);
                parts
            };
            let got = merge_touching(&boxes, join2);
            prop_assert!(got.windows(2).all(|w| w[0].1.iter().min() < w[1].1.iter().min()));
            prop_assert_eq!(sorted(got), sorted(want));
        }
    }
}

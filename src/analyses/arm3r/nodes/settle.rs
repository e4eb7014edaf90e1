//! Settling the pairs a node search leaves at the precision: touching pairs gathered into
//! clusters, each tried once by Krawczyk with ε-inflation on a box around it (`settle`, whose
//! doc says why a node can be missed by every pair of the tree). Bounded in pairs and in
//! cluster width, so a flood of candidates along a curve is left as it is.

use super::{contains, node_image, refine, width, Node};
use crate::analyses::arm3r::cusps::meet_on_torus;
use crate::analyses::arm3r::map::TorusMap;
use crate::kernel::contract::krawczyk;
use crate::kernel::interval::merge_touching;
use inari::Interval;

/// Widest cluster (its hull, in multiples of the precision) that `settle` tries.
const SETTLE_WIDTH: f64 = 64.0;

/// Pairs at the precision beyond which `settle` is not tried: clustering is quadratic in them,
/// and that many means a curve of candidates (a flood), not a few stuck nodes.
const SETTLE_PAIRS: usize = 4096;

/// True when `inner ⊂ outer` in one orientation of the pair or the other.
fn pair_inside(outer: &[[Interval; 2]; 2], inner: &[[Interval; 2]; 2]) -> bool {
    (contains(&outer[0], &inner[0]) && contains(&outer[1], &inner[1])) || (contains(&outer[0], &inner[1]) && contains(&outer[1], &inner[0]))
}

/// True when the pairs may share a point of the torus², in one orientation or the other.
fn pairs_meet(a: &[[Interval; 2]; 2], b: &[[Interval; 2]; 2]) -> bool {
    (meet_on_torus(&a[0], &b[0]) && meet_on_torus(&a[1], &b[1])) || (meet_on_torus(&a[0], &b[1]) && meet_on_torus(&a[1], &b[0]))
}

fn hull2(a: &[Interval; 2], b: &[Interval; 2]) -> [Interval; 2] {
    [a[0].convex_hull(b[0]), a[1].convex_hull(b[1])]
}

/// Touching pairs, gathered into clusters: (hull, members), by smallest member. A pair joins a
/// cluster when its two boxes touch the hull's two boxes in one orientation; it is taken in
/// that orientation.
fn clusters(pairs: &[[[Interval; 2]; 2]]) -> Vec<([[Interval; 2]; 2], Vec<usize>)> {
    let meet = |x: &[Interval; 2], y: &[Interval; 2]| (0..2).all(|i| !x[i].disjoint(y[i]));
    merge_touching(pairs, |h, b| {
        let b = if meet(&h[0], &b[0]) && meet(&h[1], &b[1]) {
            *b
        } else if meet(&h[0], &b[1]) && meet(&h[1], &b[0]) {
            [b[1], b[0]]
        } else {
            return None;
        };
        Some([hull2(&h[0], &b[0]), hull2(&h[1], &b[1])])
    })
}

/// Pairs left at the precision, settled by clusters after the search.
///
/// Why: Krawczyk proves a root only with `K(B) ⊂ int B`, so a node on (or very near) a
/// bisection line of the tree is proven in no pair when the margin it needs exceeds its
/// distance to the line. Near a cusp system (3) is ill-conditioned and that margin is large:
/// the nodes of `orthogonal_3r_near_boundary.urdf` lie 1.4e-6 from a line of the 1e-4 grid and
/// end in a ring of undecided pairs around it. So touching pairs are gathered, and Krawczyk
/// with ε-inflation (`krawczyk::inflate`) runs on a box `X ⊇` the cluster whose two halves are
/// disjoint on the torus. `K(X) ⊂ int X` proves exactly one zero `z` of system (3) in `X`, and
/// `z` is a node (`x₁ ≠ x₂`); every zero in the cluster is `z`. Then the cluster goes:
/// - an earlier node `N ⊂ X` is `z` (already reported);
/// - no earlier node meets `K(X)`: `z` is new, reported with `K(X)` tightened to the precision;
/// - otherwise (an earlier node meets `K(X)` without lying in `X`) it stays undecided.
///
/// Bounded: at most `SETTLE_PAIRS` pairs, clusters at most `SETTLE_WIDTH`·precision wide.
/// Returns which of `pairs` stay undecided, and the clusters settled; only `eligible` pairs
/// (those left at the precision) are tried.
pub(super) fn settle<M: TorusMap + ?Sized>(chain: &M, eps: f64, nodes: &mut Vec<Node>, pairs: &[[[Interval; 2]; 2]], eligible: &[bool]) -> (Vec<bool>, u64) {
    let mut keep = vec![true; pairs.len()];
    let at: Vec<usize> = (0..pairs.len()).filter(|&i| eligible[i]).collect();
    if at.len() > SETTLE_PAIRS {
        return (keep, 0);
    }
    let at_precision: Vec<[[Interval; 2]; 2]> = at.iter().map(|&i| pairs[i]).collect();
    let mut settled = 0;
    for (hull, members) in clusters(&at_precision) {
        if width(&hull[0]).max(width(&hull[1])) > SETTLE_WIDTH * eps || meet_on_torus(&hull[0], &hull[1]) {
            continue;
        }
        let x = [hull[0][0], hull[0][1], hull[1][0], hull[1][1]];
        let policy = krawczyk::Inflation { rounds: 8, own: 0.1, widest: 0.0, widest_of: &[], absolute: 1e-12, ulps: 0.0 };
        // The last trial box is the `X` whose image proved the root.
        let mut trial = x;
        let Some(k) = krawczyk::inflate(&x, &policy, |grown| {
            trial = *grown;
            node_image(chain, grown)
        }) else {
            continue;
        };
        let big = [[trial[0], trial[1]], [trial[2], trial[3]]];
        if meet_on_torus(&big[0], &big[1]) {
            continue;
        }
        let small = [[k[0], k[1]], [k[2], k[3]]];
        if nodes.iter().any(|n| pair_inside(&big, &n.theta)) {
            // the same node, already reported
        } else if nodes.iter().any(|n| pairs_meet(&n.theta, &small)) {
            continue;
        } else {
            let (a, b) = refine(chain, small[0], small[1], eps);
            let (ja, jb) = (TorusMap::jets(chain, a, 0), TorusMap::jets(chain, b, 0));
            nodes.push(Node { theta: [a, b], rho: ja.rho.value().intersection(jb.rho.value()), z: ja.z.value().intersection(jb.z.value()) });
        }
        settled += 1;
        for m in members {
            keep[at[m]] = false;
        }
    }
    (keep, settled)
}

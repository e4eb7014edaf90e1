//! One answer from what searches, and the closed form's certificates, found: each solution
//! claimed once, touching undecided cells as clusters.

use super::{Ik6Cluster, Ik6Method, Ik6Solutions};
use crate::analyses::arm6r::chain::Chain6R;
use crate::kernel::interval::{components_of_edges, touching_pairs, Interval};
use crate::kernel::search::{Stats, Status};

/// What a search of one box reported: certified boxes with the regions their certificates
/// hold on, and the cells left undecided.
pub(super) struct Searched {
    pub found: Vec<([Interval; 6], [Interval; 6])>,
    pub undecided: Vec<[Interval; 6]>,
    pub status: Status,
    pub stats: Stats,
}

/// The answer from what searches (and certificates) found: each solution claimed once, in
/// the order of the boxes' lower corners, and touching undecided cells as clusters.
pub(super) fn answer(chain: &Chain6R, mut run: Searched, method: Ik6Method) -> Ik6Solutions {
    run.found.sort_by(|a, b| a.0.iter().map(|x| x.inf()).partial_cmp(b.0.iter().map(|x| x.inf())).unwrap_or(std::cmp::Ordering::Equal));
    let mut kept: Vec<([Interval; 6], [Interval; 6])> = Vec::new();
    let inside = |k: &[Interval; 6], r: &[Interval; 6]| (0..6).all(|d| k[d].subset(r[d]));
    for (k, region) in run.found {
        // One solution claimed twice: by neighbours (its box inside the other's proof region,
        // which holds only one), or at both ends of a continuous joint's range (±π).
        if !kept.iter().any(|(u, ur)| inside(&k, ur) || inside(u, &region) || same_on_seam(chain, u, &k)) {
            kept.push((k, region));
        }
    }
    let unique: Vec<[Interval; 6]> = kept.into_iter().map(|(k, _)| k).collect();
    let undecided = run.undecided;
    let all: Vec<usize> = (0..undecided.len()).collect();
    let (contacts, _) = touching_pairs(&all, 6, |i, d| undecided[i][d]);
    let clusters = components_of_edges(undecided.len(), contacts)
        .into_iter()
        .map(|members| {
            let hull = members.iter().fold(undecided[members[0]], |h, &i| [0, 1, 2, 3, 4, 5].map(|d| h[d].convex_hull(undecided[i][d])));
            Ik6Cluster { hull, boxes: members.len() }
        })
        .collect();
    Ik6Solutions { unique, clusters, curves: Vec::new(), status: run.status, stats: run.stats, method }
}

/// Whether two boxes meet, a continuous joint's angles compared modulo a turn.
fn same_on_seam(chain: &Chain6R, a: &[Interval; 6], b: &[Interval; 6]) -> bool {
    let turn = std::f64::consts::TAU;
    (0..6).all(|d| {
        let meet = |s: f64| !(a[d].inf() > b[d].sup() + s + 1e-12 || b[d].inf() + s > a[d].sup() + 1e-12);
        meet(0.0) || (chain.continuous[d] && (meet(turn) || meet(-turn)))
    }) && (0..6).any(|d| chain.continuous[d] && a[d].disjoint(b[d]))
}


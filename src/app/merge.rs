//! A box set made smaller for a front end that must bound what it sends: boxes merged into their
//! hulls, within one cluster and one kind (solution or undecided), so that the merged set still
//! encloses every solution, keeps its components and its assembly modes' hulls, and says how
//! many boxes it came from.
//!
//! The groups of boxes merged are the leaves of a median split (on the variable whose box middles
//! spread widest), so a merged box gathers neighbours and stays about as thin as the set allows.

use super::{BoxSetResult, ResultBox, TracedBounds};
use crate::kernel::interval::Bounds;
use crate::kernel::search::BoxStatus;
use std::collections::BTreeMap;

impl BoxSetResult {
    /// Bytes its boxes take in a `linkspace_msgs/BoxSet` (the per-box columns: variable and joint
    /// bounds, status, level, cluster).
    pub fn wire_bytes(&self) -> usize {
        let per_box = 16 * (self.variables.len() + self.joint_names.len()) + 9;
        per_box * self.boxes.len()
    }

    /// The set merged (`merged`) to about `max_bytes` on the wire; `None` when it fits already.
    pub fn within_bytes(&self, max_bytes: usize) -> Option<BoxSetResult> {
        if self.wire_bytes() <= max_bytes || self.boxes.is_empty() {
            return None;
        }
        let per_box = self.wire_bytes() / self.boxes.len();
        self.merged((max_bytes / per_box).max(1))
    }

    /// The same enclosure in about `max_boxes` boxes (never fewer than one per cluster and kind):
    /// each box of the result is the hull of neighbouring boxes of one cluster (or of undecided
    /// boxes), `Unique` only where it merged nothing. `None` when the set has at most
    /// `max_boxes` boxes already.
    pub fn merged(&self, max_boxes: usize) -> Option<BoxSetResult> {
        if self.boxes.len() <= max_boxes.max(1) {
            return None;
        }
        let mut groups: BTreeMap<(bool, Option<usize>), Vec<usize>> = BTreeMap::new();
        for (i, b) in self.boxes.iter().enumerate() {
            groups.entry((b.status == BoxStatus::Undecided, b.cluster)).or_default().push(i);
        }
        let per_box = self.boxes.len().div_ceil(max_boxes.max(1));
        let mut boxes = Vec::with_capacity(max_boxes + groups.len());
        // Solution boxes first, as in every result.
        for ((_, _), members) in groups {
            let mut leaves = Vec::new();
            let parts = members.len().div_ceil(per_box);
            split(&self.boxes, members, parts, &mut leaves);
            boxes.extend(leaves.iter().filter(|leaf| !leaf.is_empty()).map(|leaf| hull(&self.boxes, leaf)));
        }
        Some(BoxSetResult { boxes, ..self.clone_without_boxes() })
    }

    fn clone_without_boxes(&self) -> BoxSetResult {
        BoxSetResult {
            mechanism: self.mechanism.clone(),
            analysis: self.analysis.clone(),
            status: self.status,
            settings: self.settings.clone(),
            variables: self.variables.clone(),
            primaries: self.primaries.clone(),
            joint_names: self.joint_names.clone(),
            fixed_joints: self.fixed_joints.clone(),
            traces: self.traces.clone(),
            boxes: Vec::new(),
            clusters: self.clusters,
            stats: self.stats.clone(),
        }
    }
}

/// The middle of a bound; NaN (a variable a box does not report) sorts last.
fn middle(b: Bounds) -> f64 {
    0.5 * (b[0] + b[1])
}

/// Splits `members` into `parts` leaves of nearly equal size, each cut across the variable whose
/// box middles spread widest.
fn split(boxes: &[ResultBox], mut members: Vec<usize>, parts: usize, leaves: &mut Vec<Vec<usize>>) {
    if parts <= 1 || members.len() <= 1 {
        leaves.push(members);
        return;
    }
    let dims = boxes[members[0]].bounds.len();
    let spread = |d: usize| {
        let (lo, hi) = members.iter().map(|&i| middle(boxes[i].bounds[d])).filter(|x| x.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
        if hi >= lo { hi - lo } else { 0.0 }
    };
    let widest = (0..dims).max_by(|&a, &b| spread(a).total_cmp(&spread(b))).unwrap_or(0);
    members.sort_by(|&a, &b| middle(boxes[a].bounds[widest]).total_cmp(&middle(boxes[b].bounds[widest])));
    let left = parts / 2;
    let upper = members.split_off(members.len() * left / parts);
    split(boxes, members, left, leaves);
    split(boxes, upper, parts - left, leaves);
}

/// The hull of two bounds; a NaN (unreported) side stays NaN, so the hull never claims a range
/// for a variable some member leaves open.
fn join(a: Bounds, b: Bounds) -> Bounds {
    if a.iter().chain(&b).any(|x| x.is_nan()) {
        return [f64::NAN, f64::NAN];
    }
    [a[0].min(b[0]), a[1].max(b[1])]
}

fn join_all(a: &mut [Bounds], b: &[Bounds]) {
    a.iter_mut().zip(b).for_each(|(x, &y)| *x = join(*x, y));
}

/// The hull of the boxes `leaf` (one cluster and kind).
fn hull(boxes: &[ResultBox], leaf: &[usize]) -> ResultBox {
    let mut out = boxes[leaf[0]].clone();
    for &i in &leaf[1..] {
        let b = &boxes[i];
        join_all(&mut out.bounds, &b.bounds);
        join_all(&mut out.joints, &b.joints);
        for (t, u) in out.traces.iter_mut().zip(&b.traces) {
            *t = TracedBounds { x: join(t.x, u.x), y: join(t.y, u.y), z: t.z.zip(u.z).map(|(p, q)| join(p, q)) };
        }
        out.level = out.level.min(b.level);
    }
    if leaf.len() > 1 && out.status == BoxStatus::Unique {
        // A hull of several boxes may hold several solutions.
        out.status = BoxStatus::Solution;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::search::{SolverSettings, Status};

    fn set(n: usize) -> BoxSetResult {
        // Two clusters on a circle of small boxes, and a few undecided boxes.
        let boxes = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                let (x, y) = (t.cos(), t.sin());
                let undecided = k % 97 == 0;
                ResultBox {
                    status: if undecided { BoxStatus::Undecided } else if k % 13 == 0 { BoxStatus::Unique } else { BoxStatus::Solution },
                    bounds: vec![[x - 1e-3, x + 1e-3], [y - 1e-3, y + 1e-3]],
                    joints: vec![[t - 1e-3, t + 1e-3]],
                    level: 10 + (k % 3) as u32,
                    cluster: if undecided { None } else { Some(usize::from(x > 0.0)) },
                    traces: Vec::new(),
                }
            })
            .collect();
        BoxSetResult {
            mechanism: "circle".into(),
            analysis: "configuration_space".into(),
            status: Status::Finished,
            settings: SolverSettings::default(),
            variables: vec!["x".into(), "y".into()],
            primaries: vec![0, 1],
            joint_names: vec!["t".into()],
            fixed_joints: Vec::new(),
            traces: Vec::new(),
            boxes,
            clusters: 2,
            stats: Default::default(),
        }
    }

    fn inside(inner: &ResultBox, outer: &ResultBox) -> bool {
        inner.bounds.iter().zip(&outer.bounds).chain(inner.joints.iter().zip(&outer.joints)).all(|(i, o)| o[0] <= i[0] && i[1] <= o[1])
    }

    #[test]
    fn every_box_lies_in_a_merged_box_of_its_cluster_and_kind() {
        let r = set(10_000);
        let m = r.merged(500).expect("merged");
        assert!(m.boxes.len() <= 500 + 3, "{} boxes", m.boxes.len());
        for b in &r.boxes {
            let undecided = b.status == BoxStatus::Undecided;
            assert!(m.boxes.iter().any(|h| h.cluster == b.cluster && (h.status == BoxStatus::Undecided) == undecided && inside(b, h)), "{b:?} is not enclosed");
        }
        // Neighbours merge: a merged solution box stays small beside the circle (the hundred
        // undecided boxes, spread around it, merge into a few long ones).
        let widest = m.boxes.iter().filter(|h| h.status != BoxStatus::Undecided).flat_map(|h| h.bounds.iter().map(|x| x[1] - x[0])).fold(0.0, f64::max);
        assert!(widest < 0.2, "a merged box is {widest} wide");
        assert!(!m.boxes.iter().any(|h| h.status == BoxStatus::Unique));
        assert_eq!(m.clusters, 2);
        assert!(m.wire_bytes() < r.wire_bytes() / 15);
        assert!(r.merged(10_000).is_none());
        let bytes = r.wire_bytes() / 10;
        assert!(r.within_bytes(bytes).expect("merged").wire_bytes() <= bytes + 3 * 57);
        assert!(r.within_bytes(r.wire_bytes()).is_none());
    }

    #[test]
    fn an_unreported_variable_stays_unreported() {
        assert!(join([f64::NAN, f64::NAN], [0.0, 1.0])[0].is_nan());
        assert_eq!(join([0.0, 1.0], [-1.0, 0.5]), [-1.0, 1.0]);
    }
}

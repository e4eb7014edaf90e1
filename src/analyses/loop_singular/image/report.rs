//! The records and JSON reports of the image searches: one cusp or node as the 3R records
//! give them (`ImageCusp`, `ImageNode`), the counts, and what `loop-singularities` writes for
//! the whole image (`ImageReport`) or one search of it (`ImagePoints`).

use super::{actuator_image, verdict, ActuatorRegions, AssemblyChangeVerdict, NodeSearch, PointSearch};
use crate::analyses::loop_singular::SingularSet;
use crate::formulate::singular::SingularProblem;
use crate::kernel::interval::Bounds;
use crate::kernel::outcome::{BoxStatus, Completeness};
use std::collections::BTreeMap;

/// One cusp: the fields of the 3R `CuspRecord`; `workspace` is the image in actuator space.
#[derive(Clone, Debug)]
pub struct ImageCusp {
    /// Free joint values (hull over the cluster).
    pub joints: BTreeMap<String, Bounds>,
    /// Its image: actuator values by joint name.
    pub workspace: BTreeMap<String, Bounds>,
    /// True when exactly one cusp is proven in the box.
    pub unique: bool,
    /// `μ` may vanish there: a corank-two point rather than a cusp (never counted proven).
    pub degenerate: bool,
    /// Why it is undecided (`None` when `unique`).
    pub reason: Option<String>,
}

/// One node: two joint boxes with a shared image (the fields of the 3R `NodeRecord`).
#[derive(Clone, Debug)]
pub struct ImageNode {
    /// The two joint boxes.
    pub points: [BTreeMap<String, Bounds>; 2],
    /// Their shared image in actuator space.
    pub workspace: BTreeMap<String, Bounds>,
    /// True when exactly one pair is proven in the two boxes.
    pub unique: bool,
}

/// Proven and undecided counts.
#[derive(Clone, Debug)]
pub struct Counts {
    /// Certified.
    pub proven: usize,
    /// Neither proven nor excluded.
    pub undecided: usize,
}

/// What `loop-singularities --kind image --json` writes.
#[derive(Clone, Debug)]
pub struct ImageReport {
    /// Robot name.
    pub mechanism: String,
    /// Actuated joints (the keys of `workspace`).
    pub actuated: Vec<String>,
    /// Complete when every search finished with nothing undecided.
    pub status: Completeness,
    /// Cusps: certified first.
    pub cusps: Vec<ImageCusp>,
    /// Node pairs.
    pub nodes: Vec<ImageNode>,
    /// Cusp counts.
    pub cusp_counts: Counts,
    /// Node counts (undecided: unproven pairs plus near-diagonal boxes).
    pub node_counts: Counts,
    /// Doubled boxes on the diagonal dropped by the injectivity certificate.
    pub injective: u64,
    /// ActuatorRegions of actuator space and their assembly modes.
    pub regions: ActuatorRegions,
    /// The verdict.
    pub verdict: AssemblyChangeVerdict,
    /// Seconds: cover, cusps, nodes, regions.
    pub seconds: [f64; 4],
}

/// The records of a cusp search: certified first.
pub fn cusp_records(sp: &SingularProblem, cusps: &PointSearch) -> Vec<ImageCusp> {
    let mut records: Vec<ImageCusp> = cusps
        .points
        .iter()
        .map(|p| {
            let joints = p.joints.clone();
            let workspace = actuator_image(sp, &joints);
            let reason = p.unproven_reason(cusps.status);
            ImageCusp { joints, workspace, unique: reason.is_none(), degenerate: p.degenerate, reason }
        })
        .collect();
    records.sort_by_key(|c| !c.unique);
    records
}

/// The records of a node search.
pub fn node_records(sp: &SingularProblem, nodes: &NodeSearch) -> Vec<ImageNode> {
    nodes
        .pairs
        .iter()
        .map(|p| {
            let (wa, wb) = (actuator_image(sp, &p.joints[0]), actuator_image(sp, &p.joints[1]));
            let workspace = wa.iter().map(|(n, x)| (n.clone(), wb.get(n).map_or(*x, |y| [x[0].max(y[0]), x[1].min(y[1])]))).collect();
            ImageNode { points: p.joints.clone(), workspace, unique: p.kind == BoxStatus::Unique }
        })
        .collect()
}

/// What `loop-singularities --kind cusps` or `--kind nodes` writes: one search of the type-II
/// image on its own, without the cover and the regions the verdict needs.
#[derive(Clone, Debug)]
pub struct ImagePoints {
    /// Robot name.
    pub mechanism: String,
    /// Actuated joints (the keys of `workspace`).
    pub actuated: Vec<String>,
    /// `cusps` or `nodes`.
    pub search: &'static str,
    /// Complete when the search finished with every point certified.
    pub status: Completeness,
    /// Cusps found (empty for a node search), certified first.
    pub cusps: Vec<ImageCusp>,
    /// Node pairs found (empty for a cusp search).
    pub nodes: Vec<ImageNode>,
    /// Certified and undecided points.
    pub counts: Counts,
    /// Node search only: doubled boxes on the diagonal dropped by the injectivity certificate.
    pub injective: u64,
    /// Seconds.
    pub seconds: f64,
}

impl ImagePoints {
    /// Whether the search finished with every point certified.
    pub fn completeness(&self) -> Completeness {
        self.status
    }

    /// The report of a cusp search.
    pub fn cusps(sp: &SingularProblem, cusps: &PointSearch) -> Self {
        let complete = Completeness::of(cusps.status, cusps.points.len() - cusps.proven(), false);
        Self {
            mechanism: sp.linkage.name.clone(),
            actuated: sp.actuated.clone(),
            search: "cusps",
            status: complete,
            cusps: cusp_records(sp, cusps),
            nodes: Vec::new(),
            counts: Counts { proven: cusps.proven(), undecided: cusps.points.len() - cusps.proven() },
            injective: 0,
            seconds: cusps.seconds,
        }
    }

    /// The report of a node search.
    pub fn nodes(sp: &SingularProblem, nodes: &NodeSearch) -> Self {
        let complete = Completeness::of(nodes.status, nodes.undecided(), false);
        Self {
            mechanism: sp.linkage.name.clone(),
            actuated: sp.actuated.clone(),
            search: "nodes",
            status: complete,
            cusps: Vec::new(),
            nodes: node_records(sp, nodes),
            counts: Counts { proven: nodes.proven(), undecided: nodes.undecided() },
            injective: nodes.injective,
            seconds: nodes.seconds,
        }
    }
}

impl ImageReport {
    /// Whether every search finished with nothing undecided.
    pub fn completeness(&self) -> Completeness {
        self.status
    }

    /// The report of the searches.
    pub fn new(sp: &SingularProblem, cover: &SingularSet, cusps: &PointSearch, nodes: &NodeSearch, regions: ActuatorRegions) -> Self {
        let cusp_records = cusp_records(sp, cusps);
        let node_records = node_records(sp, nodes);
        let regions_seconds = regions.seconds;
        let verdict = verdict(cover, cusps, nodes, &regions);
        // The one rule: no limit met and nothing undecided (an unproven cusp or node, a
        // near-diagonal box, a region whose assembly modes are not proven).
        let status = cover.status.and(cusps.status).and(nodes.status).and(regions.status);
        let open_regions = regions.regions.iter().filter(|r| r.configurations.is_none() || r.signs.is_none()).count();
        let complete = Completeness::of(status, cusps.points.len() - cusps.proven() + nodes.undecided() + open_regions, false);
        Self {
            mechanism: sp.linkage.name.clone(),
            actuated: sp.actuated.clone(),
            status: complete,
            cusps: cusp_records,
            nodes: node_records,
            cusp_counts: Counts { proven: cusps.proven(), undecided: cusps.points.len() - cusps.proven() },
            node_counts: Counts { proven: nodes.proven(), undecided: nodes.undecided() },
            injective: nodes.injective,
            regions,
            verdict,
            seconds: [cover.seconds, cusps.seconds, nodes.seconds, regions_seconds],
        }
    }
}

//! What `linkspace loop-singularities --kind image --json` writes: `singular::image::ImageReport`,
//! field for field.

use crate::interval::Bounds;
use crate::singular::image::{Counts, CuspRecord, ImageReport, NodeRecord, Region, Regions, Verdict};
use serde::Serialize;
use std::collections::BTreeMap;

/// The JSON of an `ImageReport`.
#[derive(Serialize)]
pub struct ImageJson<'a>(#[serde(with = "ImageReportDef")] pub &'a ImageReport);

#[derive(Serialize)]
#[serde(remote = "Region")]
struct RegionDef {
    cells: usize,
    sample: Vec<f64>,
    configurations: Option<usize>,
    signs: Option<[usize; 2]>,
    boxes: [usize; 3],
}

list_with!(regions, Region, "RegionDef");

#[derive(Serialize)]
#[serde(remote = "Regions")]
struct RegionsDef {
    grid: usize,
    #[serde(flatten, with = "super::kernel::StatusDef")]
    status: crate::search::Status,
    blocked_cells: usize,
    #[serde(serialize_with = "regions")]
    regions: Vec<Region>,
    seconds: f64,
}

#[derive(Serialize)]
#[serde(remote = "Verdict")]
struct VerdictDef {
    answer: &'static str,
    reason: String,
}

#[derive(Serialize)]
#[serde(remote = "CuspRecord")]
struct CuspRecordDef {
    joints: BTreeMap<String, Bounds>,
    workspace: BTreeMap<String, Bounds>,
    unique: bool,
    degenerate: bool,
}

list_with!(cusps, CuspRecord, "CuspRecordDef");

#[derive(Serialize)]
#[serde(remote = "NodeRecord")]
struct NodeRecordDef {
    points: [BTreeMap<String, Bounds>; 2],
    workspace: BTreeMap<String, Bounds>,
    unique: bool,
}

list_with!(nodes, NodeRecord, "NodeRecordDef");

#[derive(Serialize)]
#[serde(remote = "Counts")]
struct CountsDef {
    proven: usize,
    undecided: usize,
}

#[derive(Serialize)]
#[serde(remote = "ImageReport")]
struct ImageReportDef {
    mechanism: String,
    actuated: Vec<String>,
    status: &'static str,
    #[serde(serialize_with = "cusps")]
    cusps: Vec<CuspRecord>,
    #[serde(serialize_with = "nodes")]
    nodes: Vec<NodeRecord>,
    #[serde(with = "CountsDef")]
    cusp_counts: Counts,
    #[serde(with = "CountsDef")]
    node_counts: Counts,
    injective: u64,
    #[serde(with = "RegionsDef")]
    regions: Regions,
    #[serde(with = "VerdictDef")]
    verdict: Verdict,
    seconds: [f64; 4],
}

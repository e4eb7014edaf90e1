//! What `linkspace loop-singularities --kind image --json` writes: `singular::image::ImageReport`,
//! field for field.

use crate::kernel::interval::Bounds;
use crate::analyses::loop_singular::image::{ImagePoints, Counts, ImageCusp, ImageReport, ImageNode, ActuatorRegion, ActuatorRegions, AssemblyChangeVerdict};
use serde::Serialize;
use std::collections::BTreeMap;

/// The JSON of an `ImageReport`.
#[derive(Serialize)]
pub struct ImageJson<'a>(#[serde(with = "ImageReportDef")] pub &'a ImageReport);

#[derive(Serialize)]
#[serde(remote = "ActuatorRegion")]
struct ActuatorRegionDef {
    cells: usize,
    sample: Vec<f64>,
    configurations: Option<usize>,
    signs: Option<[usize; 2]>,
    boxes: [usize; 3],
}

list_with!(regions, ActuatorRegion, "ActuatorRegionDef");

#[derive(Serialize)]
#[serde(remote = "ActuatorRegions")]
struct ActuatorRegionsDef {
    grid: usize,
    #[serde(flatten, with = "super::kernel::StatusDef")]
    status: crate::kernel::search::Status,
    blocked_cells: usize,
    sign: &'static str,
    #[serde(serialize_with = "regions")]
    regions: Vec<ActuatorRegion>,
    seconds: f64,
}

#[derive(Serialize)]
#[serde(remote = "AssemblyChangeVerdict")]
struct AssemblyChangeVerdictDef {
    #[serde(serialize_with = "answer_word")]
    answer: Option<bool>,
    reason: String,
}

/// `yes`, `no` or `undecided` (`AssemblyChangeVerdict::word`).
fn answer_word<S: serde::Serializer>(answer: &Option<bool>, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(AssemblyChangeVerdict { answer: *answer, reason: String::new() }.word())
}

#[derive(Serialize)]
#[serde(remote = "ImageCusp")]
struct ImageCuspDef {
    joints: BTreeMap<String, Bounds>,
    workspace: BTreeMap<String, Bounds>,
    unique: bool,
    degenerate: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    reason: Option<String>,
}

list_with!(cusps, ImageCusp, "ImageCuspDef");

#[derive(Serialize)]
#[serde(remote = "ImageNode")]
struct ImageNodeDef {
    points: [BTreeMap<String, Bounds>; 2],
    workspace: BTreeMap<String, Bounds>,
    unique: bool,
}

list_with!(nodes, ImageNode, "ImageNodeDef");

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
    #[serde(flatten, serialize_with = "super::kernel::CompletenessDef::serialize")]
    status: crate::kernel::outcome::Completeness,
    #[serde(serialize_with = "cusps")]
    cusps: Vec<ImageCusp>,
    #[serde(serialize_with = "nodes")]
    nodes: Vec<ImageNode>,
    #[serde(with = "CountsDef")]
    cusp_counts: Counts,
    #[serde(with = "CountsDef")]
    node_counts: Counts,
    injective: u64,
    #[serde(with = "ActuatorRegionsDef")]
    regions: ActuatorRegions,
    #[serde(with = "AssemblyChangeVerdictDef")]
    verdict: AssemblyChangeVerdict,
    seconds: [f64; 4],
}

#[derive(Serialize)]
#[serde(remote = "ImagePoints")]
struct ImagePointsDef {
    mechanism: String,
    actuated: Vec<String>,
    search: &'static str,
    #[serde(flatten, serialize_with = "super::kernel::CompletenessDef::serialize")]
    status: crate::kernel::outcome::Completeness,
    #[serde(serialize_with = "cusps", skip_serializing_if = "Vec::is_empty")]
    cusps: Vec<ImageCusp>,
    #[serde(serialize_with = "nodes", skip_serializing_if = "Vec::is_empty")]
    nodes: Vec<ImageNode>,
    #[serde(with = "CountsDef")]
    counts: Counts,
    injective: u64,
    seconds: f64,
}

/// How `loop-singularities --kind cusps` and `--kind nodes` write their report.
#[derive(Serialize)]
pub struct ImagePointsJson<'a>(#[serde(with = "ImagePointsDef")] pub &'a ImagePoints);

//! How the kernel's values are written in the JSON reports. The kernel (`search`, `lp`,
//! `system`, `contract`) and `model` know no serde: the schema of what they contribute to a
//! report is stated here, field for field, with serde's remote derive (a field added to one of
//! these types and not here fails to compile).

use crate::kernel::contract::FaceBounds;
use crate::kernel::lp::{LpBackend, LpCounters};
use crate::model::rounding::Snap;
use crate::kernel::outcome::Completeness;
use crate::kernel::search::{SolveStats, SolverSettings, Status};
use crate::kernel::system::VarRole;
use serde::{Serialize, Serializer};
use std::time::Duration;


/// `Status`, flattened into its report as the completeness of a run that left nothing else
/// open: `"status": "complete"`, or `"status": "incomplete"` with `"limit"`.
pub(crate) struct StatusDef;

impl StatusDef {
    pub(crate) fn serialize<S: serde::Serializer>(status: &Status, serializer: S) -> Result<S::Ok, S::Error> {
        CompletenessDef::serialize(&Completeness::of_run(*status), serializer)
    }
}

/// `BoxStatus`, by its name: `unique`, `solution` or `undecided`.
pub(crate) fn box_status<S: serde::Serializer>(status: &crate::kernel::outcome::BoxStatus, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_str(status.name())
}

/// `Completeness`, flattened into its report: `"status"` (`complete` or `incomplete`) and, when
/// incomplete, `"limit"`: the limit that stopped a search (`boxes`, `time`, `memory`,
/// `cancelled`), else `near_degenerate`, else `undecided`.
pub(crate) struct CompletenessDef;

impl CompletenessDef {
    pub(crate) fn serialize<S: serde::Serializer>(c: &Completeness, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(None)?;
        map.serialize_entry("status", c.word())?;
        if let Some(why) = c.reason() {
            map.serialize_entry("limit", why.name())?;
        }
        map.end()
    }
}

/// `LpBackend`, as its variant name.
#[derive(Serialize)]
#[serde(remote = "LpBackend")]
pub(crate) enum LpBackendDef {
    Simplex,
    Clarabel,
}

#[derive(Serialize)]
#[serde(remote = "LpCounters")]
pub(crate) struct LpCountersDef {
    solved: u64,
    unverified: u64,
}

/// `SolverSettings`, the timeout in seconds (`null` for none).
#[derive(Serialize)]
#[serde(remote = "SolverSettings")]
pub(crate) struct SolverSettingsDef {
    sigma: f64,
    rho: f64,
    max_boxes: u64,
    #[serde(serialize_with = "seconds")]
    timeout: Option<Duration>,
    max_memory: usize,
    use_lp: bool,
    newton_width: f64,
    threads: usize,
    #[serde(with = "LpBackendDef")]
    lp_backend: LpBackend,
    scaled_widths: bool,
}

fn seconds<S: Serializer>(d: &Option<Duration>, s: S) -> Result<S::Ok, S::Error> {
    match d {
        Some(d) => s.serialize_some(&d.as_secs_f64()),
        None => s.serialize_none(),
    }
}

#[derive(Serialize)]
#[serde(remote = "SolveStats")]
pub(crate) struct SolveStatsDef {
    processed: u64,
    empty: u64,
    bisected: u64,
    solutions: u64,
    shrink_rounds: u64,
    #[serde(with = "LpCountersDef")]
    lp: LpCounters,
    certified: u64,
    spurious_dropped: u64,
    certificates_merged: u64,
    post_processing_cut_short: bool,
    max_level: u32,
    seconds: f64,
    cpu_seconds: f64,
}

/// `VarRole`: `primary` or `derived`.
#[derive(Serialize)]
#[serde(remote = "VarRole", rename_all = "snake_case")]
pub(crate) enum VarRoleDef {
    Primary,
    Derived,
}

/// `FaceBounds`: `corners` or `interval_arithmetic`.
#[derive(Serialize)]
#[serde(remote = "FaceBounds", rename_all = "snake_case")]
pub(crate) enum FaceBoundsDef {
    Corners,
    IntervalArithmetic,
}

/// Per-chart counters, as a list.
pub(crate) fn solve_stats_list<S: Serializer>(stats: &[SolveStats], s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct One<'a>(#[serde(with = "SolveStatsDef")] &'a SolveStats);
    s.collect_seq(stats.iter().map(One))
}

/// `model::rounding::Snap`: what the rounding policy changed on one joint.
#[derive(Serialize)]
#[serde(remote = "Snap")]
pub(crate) struct SnapDef {
    joint: String,
    what: String,
    original: [f64; 3],
    snapped: [f64; 3],
}

/// The rounding policy's changes, as a list of `{joint, what, original, snapped}`.
pub(crate) fn snaps<S: Serializer>(snaps: &[Snap], s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct One<'a>(#[serde(with = "SnapDef")] &'a Snap);
    s.collect_seq(snaps.iter().map(One))
}

//! Reports of `linkspace distances` (schema in README, "Distance problems"): the solution boxes
//! over the unknown squared distances and, for each, the poses or lines placed from them.
//! Pure data: no IO.

use super::Bounds;
use crate::kernel::contract::FaceBounds;
use crate::kernel::interval::{components, IntervalBox};
use crate::analyses::distances::{Certified, Choice, ClusterVerdict};
use crate::formulate::cayley_menger::{BuildOptions, CayleyMenger, Formulation};
use crate::formulate::platform::{PlatformProblem, Pose};
use crate::kernel::search::{SolveStats as Stats, SolverSettings, Status};
use nalgebra::Vector3;
use serde::{Serialize, Serializer};
use std::collections::BTreeMap;

/// A line placed from a solution: through two of the problem's points.
#[derive(Clone, Debug, Serialize)]
pub struct LineRecord {
    /// The two points it passes through.
    pub through: [String; 2],
    /// Its point nearest to the origin.
    pub point: [f64; 3],
    /// Unit direction (from the first point to the second).
    pub direction: [f64; 3],
    /// Distance (not squared) from every point with given coordinates to the line, measured in
    /// coordinates: an independent check of the point–line constraints.
    pub distance_from: BTreeMap<String, f64>,
}

/// One solution box in the user's terms.
#[derive(Clone, Debug, Serialize)]
pub struct DistanceRecord {
    /// Each unknown squared distance, e.g. `r(p1,p4)`.
    pub distances: BTreeMap<String, Bounds>,
    /// Index of the cluster (connected component) the box belongs to.
    pub cluster: usize,
    /// Platform poses placed from the box midpoint (platform problems only).
    #[serde(skip_serializing_if = "Vec::is_empty", serialize_with = "poses")]
    pub poses: Vec<Pose>,
    /// Every point's coordinates, once per placement (distance files only).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<BTreeMap<String, [f64; 3]>>,
    /// The requested lines, once per placement.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub lines: Vec<LineRecord>,
    /// Proven (Krawczyk, in the variables solved) to hold exactly one solution.
    pub unique: bool,
    /// The raw box, one interval per variable (see `variables`).
    #[serde(rename = "box")]
    pub box_: Vec<Bounds>,
    /// Depth in the search tree.
    pub level: u32,
}

/// The whole result of `linkspace distances`.
#[derive(Clone, Debug, Serialize)]
pub struct DistancesReport {
    /// Problem name (robot name or the file's `name`).
    pub problem: String,
    /// Squared distances given with `--fix`.
    pub fixed: BTreeMap<String, f64>,
    /// Formulation and whether redundant equations were added.
    #[serde(with = "BuildOptionsDef")]
    pub build: BuildOptions,
    /// How trapezoid sides were bounded.
    #[serde(with = "super::kernel::FaceBoundsDef")]
    pub faces: FaceBounds,
    /// The equations, one label each.
    pub equations: Vec<String>,
    /// The system's variables, in box order.
    pub variables: Vec<String>,
    /// Solver settings.
    #[serde(with = "super::kernel::SolverSettingsDef")]
    pub settings: SolverSettings,
    /// `complete`, or `incomplete` with the limit.
    #[serde(flatten, with = "super::kernel::StatusDef")]
    pub status: Status,
    /// Solution boxes.
    pub solutions: Vec<DistanceRecord>,
    /// The formulation solved (`points`, `shared`, `split`).
    #[serde(with = "ChoiceDef")]
    pub formulation: Choice,
    /// True when the search finished and nothing is undecided: every solution is proven and
    /// every other part of the domain proven empty.
    pub complete: bool,
    /// Distinct solutions proven (certified placements, mirror images counted apart).
    pub proven: usize,
    /// Clusters with something unproven: regions that may or may not hold solutions.
    pub undecided_regions: usize,
    /// Per cluster: proven solutions, and why it is undecided (absent when settled).
    #[serde(serialize_with = "cluster_verdicts")]
    pub cluster_verdicts: Vec<ClusterVerdict>,
    /// Connected components of the solution boxes.
    pub clusters: usize,
    /// Distinct lines (or poses): of the certified placements when there are any, else placed
    /// from the first box of each cluster; see README.
    pub placements: usize,
    /// Boxes left undecided by a limit.
    pub undecided: Vec<DistanceRecord>,
    /// Counters and time.
    #[serde(with = "super::kernel::SolveStatsDef")]
    pub stats: Stats,
}

/// `Choice`: `auto`, `points`, `line`, `shared` or `split`.
#[derive(Serialize)]
#[serde(remote = "Choice", rename_all = "snake_case")]
enum ChoiceDef {
    Auto,
    Points,
    Line,
    Shared,
    Split,
}

/// `Formulation`: `split` or `shared`.
#[derive(Serialize)]
#[serde(remote = "Formulation", rename_all = "snake_case")]
enum FormulationDef {
    Split,
    Shared,
}

#[derive(Serialize)]
#[serde(remote = "BuildOptions")]
struct BuildOptionsDef {
    #[serde(with = "FormulationDef")]
    formulation: Formulation,
    redundant: bool,
}

#[derive(Serialize)]
#[serde(remote = "ClusterVerdict")]
struct ClusterVerdictDef {
    proven: usize,
    undecided: Option<&'static str>,
    boxes: usize,
}

#[derive(Serialize)]
#[serde(remote = "Pose")]
struct PoseDef {
    position: [f64; 3],
    quaternion: [f64; 4],
    rpy: [f64; 3],
    leg_residual: f64,
}

fn poses<S: Serializer>(poses: &[Pose], s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct One<'a>(#[serde(with = "PoseDef")] &'a Pose);
    s.collect_seq(poses.iter().map(One))
}

fn cluster_verdicts<S: Serializer>(verdicts: &[ClusterVerdict], s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct One<'a>(#[serde(with = "ClusterVerdictDef")] &'a ClusterVerdict);
    s.collect_seq(verdicts.iter().map(One))
}

/// The record of one box; `platform` given for platform problems.
pub fn record(cm: &CayleyMenger, platform: Option<&PlatformProblem>, b: &IntervalBox, cluster: usize) -> DistanceRecord {
    let distances = cm.unknown_intervals(b).into_iter().map(|(n, i)| (n, [i.inf(), i.sup()])).collect();
    let (poses, points, lines) = match platform {
        Some(p) => (p.poses(cm, b), Vec::new(), Vec::new()),
        None => {
            let width = cm.unknowns.iter().map(|u| b.width(u.var)).fold(0.0, f64::max);
            let placed = cm.embed(&b.midpoint(), 1e-7 + 10.0 * width);
            let names: Vec<String> = cm.problem.points.iter().map(|q| q.name.clone()).collect();
            let points = placed.iter().map(|pts| names.iter().cloned().zip(pts.iter().copied()).collect()).collect();
            let lines = placed.iter().flat_map(|pts| cm.problem.lines.iter().map(move |&(a, c)| line(cm, pts, a, c))).collect();
            (Vec::new(), points, lines)
        }
    };
    DistanceRecord { distances, cluster, poses, points, lines, unique: false, box_: b.dims.iter().map(|d| [d.inf(), d.sup()]).collect(), level: b.level }
}

fn line(cm: &CayleyMenger, pts: &[[f64; 3]], a: usize, c: usize) -> LineRecord {
    let v = |k: usize| Vector3::new(pts[k][0], pts[k][1], pts[k][2]);
    let dir = (v(c) - v(a)).normalize();
    let foot = v(a) - dir * v(a).dot(&dir);
    let distance_from = cm
        .problem
        .points
        .iter()
        .enumerate()
        .filter(|(_, q)| q.xyz.is_some())
        .map(|(k, q)| (q.name.clone(), (v(k) - v(a)).cross(&dir).norm()))
        .collect();
    let name = |k: usize| cm.problem.points[k].name.clone();
    LineRecord { through: [name(a), name(c)], point: [foot.x, foot.y, foot.z], direction: [dir.x, dir.y, dir.z], distance_from }
}

/// Number of distinct lines (direction up to sign, within `tol`), or of distinct poses for a
/// platform, among the placements of the first box of every cluster.
pub fn distinct_placements(records: &[DistanceRecord], tol: f64) -> usize {
    // Keys seen so far, ordered by their first coordinate: a new key is compared only with
    // those within `2·tol` of it there (a margin over `tol` for the rounding of the bounds) (the same answer as comparing with all, without the
    // O(clusters²) cost on large box sets). The map's key is the coordinate's order-preserving
    // bit pattern, plus the key's index to keep equal first coordinates apart.
    let mut seen: std::collections::BTreeMap<(i64, usize), Vec<f64>> = std::collections::BTreeMap::new();
    let order = |x: f64| {
        let b = x.to_bits() as i64;
        b ^ ((b >> 63) as u64 >> 1) as i64
    };
    let mut clusters_seen = std::collections::BTreeSet::new();
    for r in records {
        if !clusters_seen.insert(r.cluster) {
            continue;
        }
        let keys: Vec<Vec<f64>> = if r.poses.is_empty() {
            r.lines
                .iter()
                .map(|l| {
                    // A line up to orientation: its foot point and the direction with a positive
                    // first significant component.
                    let s = if l.direction.iter().find(|c| c.abs() > 1e-9).is_some_and(|c| *c < 0.0) { -1.0 } else { 1.0 };
                    vec![l.point[0], l.point[1], l.point[2], s * l.direction[0], s * l.direction[1], s * l.direction[2]]
                })
                .collect()
        } else {
            // q and −q are the same rotation.
            r.poses
                .iter()
                .map(|p| {
                    let s = if p.quaternion[0] < 0.0 { -1.0 } else { 1.0 };
                    p.position.iter().copied().chain(p.quaternion.iter().map(|x| s * x)).collect()
                })
                .collect()
        };
        for k in keys {
            let Some(&first) = k.first() else {
                // A key of no coordinate matches every other such key.
                seen.entry((i64::MIN, 0)).or_insert(k);
                continue;
            };
            let near = |s: &Vec<f64>| s.iter().zip(&k).all(|(a, b)| (a - b).abs() <= tol);
            // NaN coordinates match nothing: such a key is distinct, as with the full scan.
            let found = !first.is_nan() && seen.range((order(first - 2.0 * tol), 0)..=(order(first + 2.0 * tol), usize::MAX)).any(|(_, s)| near(s));
            if !found {
                let id = seen.len() + 1;
                seen.insert((order(first), id), k);
            }
        }
    }
    seen.len()
}

/// The report of a finished run.
#[allow(clippy::too_many_arguments)]
pub fn report(cm: &CayleyMenger, platform: Option<&PlatformProblem>, fixed: BTreeMap<String, f64>, faces: FaceBounds, settings: &SolverSettings, status: Status, stats: Stats, solutions: &[IntervalBox], undecided: &[IntervalBox]) -> DistancesReport {
    let (labels, clusters) = components(solutions);
    let records: Vec<DistanceRecord> = solutions.iter().zip(&labels).map(|(b, &l)| record(cm, platform, b, l)).collect();
    let tol = 10.0 * settings.sigma.max(1e-6);
    DistancesReport {
        problem: cm.problem.name.clone(),
        fixed,
        build: cm.options,
        faces,
        equations: cm.labels.clone(),
        variables: cm.system.vars.iter().map(|v| v.name.clone()).collect(),
        settings: settings.clone(),
        status,
        placements: distinct_placements(&records, tol),
        solutions: records,
        formulation: if cm.options.formulation == Formulation::Split { Choice::Split } else { Choice::Shared },
        complete: false,
        proven: 0,
        undecided_regions: clusters,
        cluster_verdicts: vec![ClusterVerdict { proven: 0, undecided: Some("not certified: this report does not certify"), boxes: 0 }; clusters],
        clusters,
        undecided: undecided.iter().map(|b| record(cm, platform, b, usize::MAX)).collect(),
        stats,
    }
}

impl DistancesReport {
    /// The report of a distances answer.
    pub fn of(a: &crate::app::DistancesAnswer) -> DistancesReport {
        report_certified(&a.certified, a.run.platform_problem(), a.run.fixed().iter().cloned().collect(), a.request.faces, &a.settings)
    }
}

/// The report of a certified run (`distances::solve`): boxes with their `unique` flags, clusters
/// with their verdicts, and "N proven, M undecided".
pub fn report_certified(c: &Certified, platform: Option<&PlatformProblem>, fixed: BTreeMap<String, f64>, faces: FaceBounds, settings: &SolverSettings) -> DistancesReport {
    // Placements are compared within ten times the widest box (sigma for the determinants'
    // boxes; far less for the tiny certified boxes of the coordinate formulations).
    let widest = c.solutions.iter().flat_map(|b| b.dims.iter().map(|d| d.wid())).fold(0.0, f64::max);
    let tol = 10.0 * widest.min(settings.sigma).max(1e-6);
    let mut rep = report(&c.cm, platform, fixed, faces, settings, c.status, c.stats.clone(), &[], &[]);
    let records: Vec<DistanceRecord> = match (&c.placed, c.formulation) {
        (Some(pl), Choice::Points | Choice::Line) => c.solutions.iter().zip(&c.cluster).zip(&c.tags).map(|((b, &l), &t)| placed_record(c, pl, platform, b, l, t == crate::kernel::outcome::BoxStatus::Unique)).collect(),
        _ => c.solutions.iter().zip(&c.cluster).zip(&c.tags).map(|((b, &l), &t)| DistanceRecord { unique: t == crate::kernel::outcome::BoxStatus::Unique, ..record(&c.cm, platform, b, l) }).collect(),
    };
    rep.undecided = match (&c.placed, c.formulation) {
        (Some(pl), Choice::Points | Choice::Line) => c.undecided.iter().map(|b| placed_record(c, pl, platform, b, usize::MAX, false)).collect(),
        _ => c.undecided.iter().map(|b| record(&c.cm, platform, b, usize::MAX)).collect(),
    };
    if matches!(c.formulation, Choice::Points | Choice::Line) {
        if let Some(pl) = &c.placed {
            rep.equations = pl.labels.clone();
            rep.variables = pl.system.vars.iter().map(|v| v.name.clone()).collect();
        }
    }
    // Distinct placements: of the certified roots when there are any. Placed from box
    // midpoints and compared within ten times the box width (the rule for uncertified reports),
    // they undercounted at coarse sigma: at sigma 0.1 two poses of octahedral b less than a unit
    // apart in position and quaternion merged (6 for 16). The roots are polished Newton points
    // in tiny certified boxes, so they are compared within 1e-6.
    rep.placements = if c.roots.is_empty() {
        distinct_placements(&records, tol)
    } else {
        let at_roots: Vec<DistanceRecord> = c
            .roots
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let (poses, lines) = match platform {
                    Some(p) => (p.pose_of(&r.points).into_iter().collect(), Vec::new()),
                    None => (Vec::new(), c.cm.problem.lines.iter().map(|&(a, e)| line(&c.cm, &r.points, a, e)).collect()),
                };
                DistanceRecord { distances: BTreeMap::new(), cluster: k, poses, points: Vec::new(), lines, unique: true, box_: Vec::new(), level: 0 }
            })
            .collect();
        distinct_placements(&at_roots, 1e-6)
    };
    rep.solutions = records;
    rep.formulation = c.formulation;
    rep.proven = c.proven();
    rep.complete = c.complete();
    rep.undecided_regions = c.undecided_regions();
    rep.cluster_verdicts = c.clusters.clone();
    rep.clusters = c.clusters.len();
    rep
}

/// A box of the points formulation: coordinates at its midpoint, distances enclosed over it.
fn placed_record(c: &Certified, pl: &crate::formulate::coordinates::Placed, platform: Option<&PlatformProblem>, b: &IntervalBox, cluster: usize, unique: bool) -> DistanceRecord {
    let distances = c.cm.unknowns.iter().map(|u| {
        let d = pl.distance_over(u.a, u.b, b);
        (u.name.clone(), [d.inf(), d.sup()])
    }).collect();
    let pts = pl.points(&b.midpoint());
    let (poses, points, lines) = match platform {
        Some(p) => (p.pose_of(&pts).into_iter().collect(), Vec::new(), Vec::new()),
        None => {
            let names = c.cm.problem.points.iter().map(|q| q.name.clone());
            let points = vec![names.zip(pts.iter().copied()).collect()];
            let lines = c.cm.problem.lines.iter().map(|&(a, e)| line(&c.cm, &pts, a, e)).collect();
            (Vec::new(), points, lines)
        }
    };
    DistanceRecord { distances, cluster, poses, points, lines, unique, box_: b.dims.iter().map(|d| [d.inf(), d.sup()]).collect(), level: b.level }
}

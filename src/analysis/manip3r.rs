//! The 3R-manipulator analysis: certified cusps, nodes and internal motions (`crate::manip3r`),
//! a cover of the singular curves, inverse kinematics of a point, and where a configuration
//! lies relative to the singular set.
//!
//! Cusps, nodes, internal motions and inverse-kinematics boxes are those of `linkspace
//! singularities --json` and `linkspace ik --json` for the same URDF and settings (same
//! searches, same order). The curve cover and the classification are built here.
//!
//! An open 3R chain reaches every joint configuration, so there is no configuration space to
//! solve; the default `configuration_space` and `solve` answer "not available".

use super::{
    gap, Analysis, AnalysisError, Bounds, BoxSetResult, Classification, IkQuery, IkResult, IkSolution, PreparedRun, ResultBox, Service, SingularPair, SingularPoint,
    SingularityQuery, SingularityResult,
};
use crate::interval::{interval, point};
use crate::manip3r::motion;
use crate::manip3r::report::radius;
use crate::manip3r::branches::SingularBranches;
use crate::manip3r::curves::Cover;
use crate::manip3r::{self, ik, Chain3R, Manip3rError};
use crate::model::Mechanism;
use crate::search::{BoxStatus, Limit, Limits, Progress, SolveStats as Stats, SolverSettings, Status};
use inari::Interval;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

/// Bisections per axis of the singular-curve cover: 256 × 256 cells of about 0.025 rad, the
/// grid of the README's charts. Fine enough to show the curves and to separate the regions
/// between them, coarse enough for a message of a few thousand boxes.
pub const CURVE_DEPTH: u32 = 8;

type V3 = [Interval; 3];

fn dot(a: &V3, b: &V3) -> Interval {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn bounds(x: Interval) -> Bounds {
    [x.inf(), x.sup()]
}

/// A serial chain of three revolute joints, as loaded.
#[derive(Clone, Debug)]
pub struct Manip3rAnalysis {
    chain: Arc<Chain3R>,
    /// The first joint's frame in the root link's: rotation (rows) and translation.
    base_rotation: [V3; 3],
    base_translation: V3,
    /// The first axis in the first joint's frame, and two unit vectors completing a
    /// right-handed basis (`e1 × e2 = axis`).
    axis: V3,
    e1: V3,
    e2: V3,
    /// Cover of the singular curves, computed once (it does not depend on any request).
    cover: Arc<Cover>,
    /// The reduced mechanism the chain was built from (rounded), for the verdict.
    reduced: Arc<Mechanism>,
    /// Limits of the three joints, as the CLI reads them (the verdict's cusp must lie inside).
    limits: Arc<manip3r::limits::JointLimits>,
    /// Axes 2 and 3 parallel (`verdict::parallel_structure`): the verdict is structural and
    /// the interval searches are not run, as in `linkspace singularities`.
    structural: bool,
    /// The certified singular branches (parallel axes 2 and 3), computed once.
    branches: Option<Arc<SingularBranches>>,
}

impl Manip3rAnalysis {
    /// Reads the chain (nominal geometry); errors when the mechanism is not a 3R chain or its
    /// map is degenerate.
    pub fn new(mechanism: &Mechanism) -> Result<Self, Manip3rError> {
        // As the CLI reads files: rounding policy, then the positioning structure of a real arm
        // (root to wrist centre or tip), so the node takes vendor URDFs too.
        let prepared = manip3r::prepare(mechanism, &manip3r::LoadOptions::default())?;
        let mechanism = &prepared.mechanism;
        let chain = Chain3R::from_mechanism(mechanism, 0.0)?;
        let first = mechanism.joint(&chain.joints[0]).expect("invariant: the chain names its joints");
        // Compose the joint origins from the root down to the first revolute joint, in interval
        // arithmetic (as `Chain3R` does for the rest of the chain).
        let mut r: [V3; 3] = [[point(1.0), point(0.0), point(0.0)], [point(0.0), point(1.0), point(0.0)], [point(0.0), point(0.0), point(1.0)]];
        let mut t: V3 = [point(0.0); 3];
        for j in mechanism.path_to(mechanism.joints[first].child) {
            let iso = &mechanism.joints[j].origin;
            let m = mechanism.joints[j].rotation_matrix();
            let o: [V3; 3] = [0, 1, 2].map(|i| [0, 1, 2].map(|k| point(m[i][k])));
            let v = iso.translation.vector;
            let ov: V3 = [point(v[0]), point(v[1]), point(v[2])];
            // (r, t) ∘ (o, ov) = (r·o, r·ov + t)
            let rows = r;
            r = [0, 1, 2].map(|i| [0, 1, 2].map(|k| rows[i][0] * o[0][k] + rows[i][1] * o[1][k] + rows[i][2] * o[2][k]));
            t = [0, 1, 2].map(|i| dot(&rows[i], &ov) + t[i]);
        }
        let a = mechanism.joints[first].axis;
        let axis = [point(a[0]), point(a[1]), point(a[2])];
        // e1: the unit vector of the coordinate axis least aligned with a₁, made perpendicular.
        let k = (0..3).min_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs())).expect("three axes");
        let mut u = [0.0; 3];
        u[k] = 1.0;
        let d = a[k];
        let mut e1 = [u[0] - d * a[0], u[1] - d * a[1], u[2] - d * a[2]];
        let n = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
        e1 = e1.map(|x| x / n);
        let e2 = [a[1] * e1[2] - a[2] * e1[1], a[2] * e1[0] - a[0] * e1[2], a[0] * e1[1] - a[1] * e1[0]];
        let cover = Arc::new(Cover::new(&chain, CURVE_DEPTH, &manip3r::Control::with_limits(Limits::default())));
        let structural = manip3r::verdict::parallel_structure(mechanism).is_some();
        let branches = manip3r::branches::of(mechanism, &chain).map(Arc::new);
        Ok(Self {
            chain: Arc::new(chain),
            base_rotation: r,
            base_translation: t,
            axis,
            e1: e1.map(point),
            e2: e2.map(point),
            cover,
            reduced: Arc::new(prepared.mechanism.clone()),
            limits: Arc::new(prepared.limits.clone()),
            structural,
            branches,
        })
    }

    /// The chain's name tokens for records over (θ₂, θ₃).
    fn record_joints(&self) -> Vec<String> {
        vec![self.chain.joints[1].clone(), self.chain.joints[2].clone()]
    }

    /// The point `p` (root frame) in the first joint's frame: `Rᵀ(p − t)`, the rotation taken
    /// as exact (as every URDF rotation is in this crate).
    fn to_first_joint(&self, p: [f64; 3]) -> V3 {
        let d: V3 = [0, 1, 2].map(|i| point(p[i]) - self.base_translation[i]);
        let r = &self.base_rotation;
        [0, 1, 2].map(|k| r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2])
    }

    /// Direction about the first axis of a vector perpendicular to it (radians), or `None` when
    /// it may vanish.
    fn direction(&self, v: &V3) -> Option<Interval> {
        direction(dot(v, &self.e1), dot(v, &self.e2))
    }
}

/// An enclosure of the angle of every vector (x, y) of the box, or `None` when the box may hold
/// the origin or spans half a turn or more.
///
/// The candidate comes from `f64::atan2` at the corners; it is then proven: every vector of the
/// box lies left of direction α (`cos α·y − sin α·x ≥ 0`) and right of direction β, evaluated
/// with the sound interval sine and cosine, and β − α < π, so every angle lies in [α, β]
/// (modulo 2π). A failed proof widens the candidate, then gives up.
fn direction(x: Interval, y: Interval) -> Option<Interval> {
    if x.contains(0.0) && y.contains(0.0) {
        return None;
    }
    let centre = y.mid().atan2(x.mid());
    let wrap = |a: f64| {
        let tau = std::f64::consts::TAU;
        a - tau * (a / tau).round()
    };
    let rel: Vec<f64> = [(x.inf(), y.inf()), (x.inf(), y.sup()), (x.sup(), y.inf()), (x.sup(), y.sup())].iter().map(|&(a, b)| wrap(b.atan2(a) - centre)).collect();
    let lo = centre + rel.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = centre + rel.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    for margin in [1e-12, 1e-9, 1e-6] {
        let (alpha, beta) = (lo - margin, hi + margin);
        if beta - alpha >= 3.0 {
            return None;
        }
        let side = |angle: f64| {
            let a = point(angle);
            crate::interval::trig::cos(a) * y - crate::interval::trig::sin(a) * x
        };
        if side(alpha).inf() >= 0.0 && side(beta).sup() <= 0.0 {
            return Some(interval(alpha, beta));
        }
    }
    None
}

/// Shifts an angle interval by a whole number of turns so that its middle lies in [-π, π].
fn principal(a: Interval) -> Interval {
    let k = (a.mid() / std::f64::consts::TAU).round();
    if k == 0.0 {
        a
    } else {
        a - point(k) * Interval::TAU
    }
}

impl Analysis for Manip3rAnalysis {
    fn mechanism(&self) -> &str {
        &self.chain.name
    }

    fn kind(&self) -> &'static str {
        "manipulator_3r"
    }

    fn services(&self) -> Vec<Service> {
        vec![Service::Singularities, Service::InverseKinematics, Service::Classify]
    }

    fn limitation(&self) -> String {
        "a 3R manipulator: an open chain reaches every joint configuration, so there is no configuration space to solve (singularities, inverse_kinematics and classify are answered)".to_string()
    }

    fn free_joints(&self) -> Vec<String> {
        self.chain.joints.to_vec()
    }

    fn fixed_joints(&self) -> Vec<(String, f64)> {
        Vec::new()
    }

    fn periodic(&self) -> Vec<bool> {
        vec![true; 3]
    }

    fn singularities(&self, query: &SingularityQuery) -> Result<Box<dyn PreparedRun<SingularityResult>>, AnalysisError> {
        manip3r::check_precision(query.precision).map_err(|e| AnalysisError::BadRequest(e.to_string()))?;
        if query.max_boxes == 0 {
            return Err(AnalysisError::BadRequest("max_boxes must be at least 1".into()));
        }
        Ok(Box::new(SingularityRun {
            chain: self.chain.clone(),
            cover: self.cover.clone(),
            query: query.clone(),
            joints: self.record_joints(),
            reduced: self.reduced.clone(),
            limits: self.limits.clone(),
            structural: self.structural,
            branches: self.branches.clone(),
        }))
    }

    fn inverse_kinematics(&self, query: &IkQuery) -> Result<Box<dyn PreparedRun<IkResult>>, AnalysisError> {
        let p = query.point;
        if p.iter().any(|v| !v.is_finite()) {
            return Err(AnalysisError::BadRequest(format!("point ({}, {}, {}) is not finite", p[0], p[1], p[2])));
        }
        manip3r::check_precision(query.precision).map_err(|e| AnalysisError::BadRequest(e.to_string()))?;
        if query.max_boxes == 0 {
            return Err(AnalysisError::BadRequest("max_boxes must be at least 1".into()));
        }
        let local = self.to_first_joint(p);
        let z = dot(&local, &self.axis);
        let perp: V3 = [0, 1, 2].map(|i| local[i] - z * self.axis[i]);
        let rho = dot(&perp, &perp).intersection(interval(0.0, f64::INFINITY));
        Ok(Box::new(IkRun { analysis: self.clone(), query: query.clone(), target: [rho, z], target_direction: self.direction(&perp) }))
    }

    fn classify(&self, values: &[f64], _cspace: Option<&BoxSetResult>, _singular: Option<&SingularityResult>) -> Result<Classification, AnalysisError> {
        let c = &self.cover;
        let (t2, t3) = (values[1], values[2]);
        let distance = c.boxes.iter().map(|&(i, j)| (gap(t2, c.bounds(i), true).powi(2) + gap(t3, c.bounds(j), true).powi(2)).sqrt()).fold(f64::INFINITY, f64::min);
        let region = c.cell_of(t2, t3).map(|(i, j)| c.region[i * c.n + j]).filter(|&r| r >= 0);
        let note = match region {
            Some(r) => format!(
                "an open 3R chain: every configuration is reachable. Component {r} of {} is a connected region of cells proven free of singularities (det Df keeps one sign there), so it lies in one aspect; two regions may still belong to one aspect. The singular distance is a lower bound on the distance in (θ2, θ3) to the singular set, which lies in the {} boxes of the {CURVE_DEPTH}-level cover",
                c.regions,
                c.boxes.len()
            ),
            None => format!("an open 3R chain: every configuration is reachable. This one lies in a box of the singular-curve cover (det Df may vanish there), so it belongs to no proven region (component -1); the singular distance is 0"),
        };
        Ok(Classification {
            inside: true,
            component: region.map(|r| r as usize),
            components: c.regions,
            distance: 0.0,
            singular_distance: Some(if region.is_some() { distance } else { 0.0 }),
            note,
        })
    }
}

/// The cover as a box set over (θ₂, θ₃).
fn box_set(cover: &Cover, mechanism: &str, joints: &[String]) -> BoxSetResult {
    let boxes = cover
        .boxes
        .iter()
        .zip(&cover.cluster)
        .map(|(&(i, j), &c)| {
            let b = vec![cover.bounds(i), cover.bounds(j)];
            ResultBox { status: BoxStatus::Solution, bounds: b.clone(), joints: b, level: 2 * CURVE_DEPTH, cluster: Some(c), traces: vec![] }
        })
        .collect();
    let width = cover.line(1) - cover.line(0);
    BoxSetResult {
        mechanism: mechanism.to_string(),
        analysis: "singular_curves".into(),
        status: Status::Complete,
        settings: SolverSettings { sigma: width, max_boxes: cover.stats.processed, timeout: None, ..Default::default() },
        variables: joints.to_vec(),
        primaries: vec![0, 1],
        joint_names: joints.to_vec(),
        fixed_joints: vec![],
        traces: vec![],
        boxes,
        clusters: cover.clusters,
        stats: Stats { processed: cover.stats.processed, solutions: cover.boxes.len() as u64, max_level: 2 * CURVE_DEPTH, seconds: cover.seconds, ..Default::default() },
    }
}

/// A validated singularity run.
struct SingularityRun {
    chain: Arc<Chain3R>,
    cover: Arc<Cover>,
    query: SingularityQuery,
    joints: Vec<String>,
    reduced: Arc<Mechanism>,
    limits: Arc<manip3r::limits::JointLimits>,
    structural: bool,
    branches: Option<Arc<SingularBranches>>,
}

impl PreparedRun<SingularityResult> for SingularityRun {
    fn run(self: Box<Self>, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> SingularityResult {
        let (chain, q) = (&*self.chain, &self.query);
        let limits = Limits { max_cells: q.max_boxes, timeout: q.timeout, ..Limits::default() };
        let control = manip3r::Control { limits, threads: q.threads.max(1), cancel };
        let start = std::time::Instant::now();
        // As `linkspace singularities`: with axes 2 and 3 parallel the verdict's proof replaces
        // the cusp search (which cannot complete there) and nodes are not searched; whenever
        // the singular branches are known, whole branches are curves of nodes, which the
        // isolated-node search does not model.
        let with_nodes = q.nodes && self.branches.is_none();
        let run = if self.structural {
            manip3r::structural_singularities(chain, q.precision).expect("invariant: precision validated when prepared")
        } else {
            manip3r::singularities(chain, q.precision, with_nodes, &control, progress).expect("invariant: precision validated when prepared")
        };
        // The verdict reads the full-torus run (the CLI's, before its joint-limit filter).
        let verdict = manip3r::verdict::decide(&self.reduced, chain, &run, &self.limits, &control.remaining_since(start));
        // Then the file's joint limits filter what is published, as the CLI's do.
        let mut run = run;
        let effect = self.limits.restrict().then(|| self.limits.apply(&mut run));
        let (found, node_search) = (&run.cusps, &run.nodes);
        let two = |t: &[Interval; 2]| vec![bounds(t[0]), bounds(t[1])];
        let image = |t: [Interval; 2]| {
            let j = chain.jets(t, 0);
            [j.rho.value(), j.z.value()]
        };
        let workspace = |rho: Interval, z: Interval| vec![bounds(radius(rho)), bounds(z)];
        let mut cusp_records: Vec<SingularPoint> = found.cusps.iter().map(|c| SingularPoint { joints: two(&c.theta), workspace: workspace(c.rho, c.z), certified: c.unique }).collect();
        cusp_records.extend(found.undecided.iter().map(|u| {
            let [rho, z] = image(u.theta);
            SingularPoint { joints: two(&u.theta), workspace: workspace(rho, z), certified: false }
        }));
        let mut node_records = Vec::new();
        if let Some(n) = &node_search {
            node_records.extend(n.nodes.iter().map(|n| SingularPair { joints: [two(&n.theta[0]), two(&n.theta[1])], workspace: workspace(n.rho, n.z), certified: true }));
            node_records.extend(n.undecided.iter().map(|p| {
                let (a, b) = (image(p[0]), image(p[1]));
                SingularPair { joints: [two(&p[0]), two(&p[1])], workspace: workspace(a[0].convex_hull(b[0]), a[1].convex_hull(b[1])), certified: false }
            }));
        }
        let status = run.status;
        let motions = internal_motions(chain, &found.bands, &self.joints, q.precision);
        let processed = found.stats.processed + node_search.as_ref().map_or(0, |n| n.stats.processed);
        let certified_nodes = node_search.as_ref().map_or(0, |n| n.nodes.len());
        let summary = format!(
            "{} cusps, {}, {} internal-motion lines, {} undecided, {} cover boxes in {} pieces, {}",
            found.cusps.len(),
            if with_nodes { format!("{certified_nodes} nodes") } else if q.nodes { "nodes not searched (the singular branches are curves of nodes)".to_string() } else { "nodes not searched".to_string() },
            found.bands.len(),
            found.undecided.len() + node_search.as_ref().map_or(0, |n| n.undecided.len()),
            self.cover.boxes.len(),
            self.cover.clusters,
            match status {
                Status::Complete => "complete".to_string(),
                Status::Incomplete(Limit::Cancelled) => "incomplete (cancelled)".to_string(),
                Status::Incomplete(Limit::Boxes) => "incomplete (box limit)".to_string(),
                Status::Incomplete(limit) => format!("incomplete ({} limit)", limit.name()),
            }
        );
        SingularityResult {
            mechanism: chain.name.clone(),
            status,
            query: q.clone(),
            joint_names: self.joints.clone(),
            workspace_names: vec!["radius".into(), "z".into()],
            cusps: cusp_records,
            nodes: node_records,
            singular_curves: box_set(&self.cover, &chain.name, &self.joints),
            internal_motions: motions,
            processed,
            seconds: start.elapsed().as_secs_f64() + self.cover.seconds,
            summary: match &effect {
                Some(e) => format!("{}; {}; {}", verdict.line(), summary, e.text),
                None => format!("{}; {}", verdict.line(), summary),
            },
            loops: None,
            verdict: Some(verdict),
            branches: self.branches.as_deref().cloned(),
        }
    }
}

/// The internal-motion lines as a box set: θ₂ over its whole range, θ₃ in each band's
/// enclosure of the lines (as `MotionRecord` of the CLI report).
fn internal_motions(chain: &Chain3R, bands: &[motion::Band], joints: &[String], precision: f64) -> BoxSetResult {
    let full = motion::full_range();
    let boxes = bands
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let bx = vec![bounds(full), b.theta3];
            // A near-degenerate strip (`Band::near`) is not an internal motion: undecided.
            let status = if b.near.is_some() { BoxStatus::Undecided } else { BoxStatus::Solution };
            ResultBox { status, bounds: bx.clone(), joints: bx, level: 0, cluster: Some(k), traces: vec![] }
        })
        .collect();
    BoxSetResult {
        mechanism: chain.name.clone(),
        analysis: "internal_motions".into(),
        status: Status::Complete,
        settings: SolverSettings { sigma: precision, ..Default::default() },
        variables: joints.to_vec(),
        primaries: vec![1],
        joint_names: joints.to_vec(),
        fixed_joints: vec![],
        traces: vec![],
        boxes,
        clusters: bands.len(),
        stats: Stats { solutions: bands.len() as u64, ..Default::default() },
    }
}

/// A validated inverse-kinematics run.
struct IkRun {
    analysis: Manip3rAnalysis,
    query: IkQuery,
    /// (ρ, z) of the point in the first joint's frame.
    target: [Interval; 2],
    /// Direction of the point about the first axis (`None` on the axis: θ₁ is free).
    target_direction: Option<Interval>,
}

impl PreparedRun<IkResult> for IkRun {
    fn run(self: Box<Self>, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> IkResult {
        let start = Instant::now();
        let a = &self.analysis;
        let chain = &*a.chain;
        let limits = Limits { max_cells: self.query.max_boxes, timeout: self.query.timeout, ..Limits::default() };
        let control = manip3r::Control { limits, threads: self.query.threads.max(1), cancel };
        let mut s = ik::solve_target(chain, self.target, self.query.precision, &control, progress).expect("invariant: validated when prepared");
        // Solutions outside the file's joint limits are not solutions of the arm (`ik` drops
        // them too); those on a limit are kept.
        if a.limits.restrict() {
            a.limits.apply_ik(&mut s);
        }
        // θ₁ turns the end point's direction about a₁ onto the point's.
        let theta1 = |b: &[Interval; 2]| -> Bounds {
            match (self.target_direction, a.direction(&chain.perp(*b))) {
                (Some(t), Some(u)) => bounds(principal(t - u)),
                _ => bounds(motion::full_range()),
            }
        };
        let three = |b: &[Interval; 2]| vec![theta1(b), bounds(b[0]), bounds(b[1])];
        let mut solutions: Vec<IkSolution> = s.unique.iter().map(|b| IkSolution { joints: three(b), unique: true, boxes: 0 }).collect();
        solutions.extend(s.clusters.iter().map(|c| IkSolution { joints: three(&c.hull), unique: false, boxes: c.boxes }));
        IkResult {
            mechanism: chain.name.clone(),
            joint_names: chain.joints.to_vec(),
            point_names: vec!["radius".into(), "z".into()],
            point_values: vec![bounds(radius(self.target[0])), bounds(self.target[1])],
            solutions,
            status: s.status,
            processed: s.stats.processed,
            seconds: start.elapsed().as_secs_f64(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::load;
    use crate::model::{urdf, JointKind};
    use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};

    const E: &str = include_str!("../../urdf/orthogonal_3r_e.urdf");
    const F: &str = include_str!("../../urdf/orthogonal_3r_f.urdf");

    fn query() -> SingularityQuery {
        SingularityQuery { precision: 1e-4, nodes: true, max_boxes: 1_000_000, timeout: None, threads: 1 }
    }

    fn revolute(m: &Mechanism) -> Vec<String> {
        m.joints.iter().filter(|j| matches!(j.kind, JointKind::Revolute { .. })).map(|j| j.name.clone()).collect()
    }

    /// The tip's position in the root frame at joint values `q`, in floating point.
    fn forward(m: &Mechanism, q: &[f64]) -> [f64; 3] {
        let names = revolute(m);
        let tip = (0..m.links.len()).find(|&l| m.joints.iter().all(|j| j.parent != l)).expect("a leaf");
        let mut pose = Isometry3::identity();
        for j in m.path_to(tip) {
            let joint = &m.joints[j];
            pose *= joint.origin;
            if let Some(k) = names.iter().position(|n| *n == joint.name) {
                pose *= Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(joint.axis), q[k]));
            }
        }
        let p = pose * Point3::origin();
        [p.x, p.y, p.z]
    }

    #[test]
    fn robot_e_has_the_table_counts_and_a_sound_curve_cover() {
        let m = urdf::parse(E).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        assert_eq!(a.kind(), "manipulator_3r");
        let r = a.singularities(&query()).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(r.status, Status::Complete);
        assert_eq!((r.cusps.iter().filter(|c| c.certified).count(), r.nodes.iter().filter(|n| n.certified).count(), r.undecided()), (4, 2, 0));
        assert_eq!(r.internal_motions.boxes.len(), 0);
        // Every point where det Df changes sign along a fine grid line lies in a cover box.
        let chain = Chain3R::from_mechanism(&m, 0.0).expect("3R");
        let cover = &r.singular_curves;
        let det = |t2: f64, t3: f64| chain.jets([point(t2), point(t3)], 1).det().value().mid();
        let inside = |t2: f64, t3: f64| cover.boxes.iter().any(|b| b.joints[0][0] <= t2 && t2 <= b.joints[0][1] && b.joints[1][0] <= t3 && t3 <= b.joints[1][1]);
        let mut crossings = 0;
        for k in 0..200 {
            let t3 = -3.1 + 6.2 * k as f64 / 199.0;
            let n = 4000;
            for i in 0..n {
                let (x0, x1) = (-3.14 + 6.28 * i as f64 / n as f64, -3.14 + 6.28 * (i + 1) as f64 / n as f64);
                if det(x0, t3).signum() != det(x1, t3).signum() {
                    crossings += 1;
                    assert!(inside(x0, t3) || inside(x1, t3), "sign change of det at θ2 ≈ {x0}, θ3 = {t3} outside the cover");
                }
            }
        }
        assert!(crossings > 200, "the test must see the curves: {crossings} crossings");
        // The cover is thin: far fewer boxes than the grid.
        assert!(cover.boxes.len() < 256 * 256 / 10, "{} boxes", cover.boxes.len());
    }

    #[test]
    fn classification_gives_a_sound_lower_bound_on_the_singular_distance() {
        let m = urdf::parse(E).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        let chain = Chain3R::from_mechanism(&m, 0.0).expect("3R");
        // A cusp's own configuration is singular: distance 0, no region.
        let r = a.singularities(&query()).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        let c = &r.cusps[0].joints;
        let at_cusp = a.classify(&[0.3, 0.5 * (c[0][0] + c[0][1]), 0.5 * (c[1][0] + c[1][1])], None, Some(&r)).expect("3R classifies");
        assert_eq!((at_cusp.component, at_cusp.singular_distance), (None, Some(0.0)));
        // Regular configurations: the distance to the nearest sampled singular point is at
        // least the reported bound, and every sample is in a region.
        let det = |t2: f64, t3: f64| chain.jets([point(t2), point(t3)], 1).det().value().mid();
        let mut singular = Vec::new();
        for k in 0..400 {
            let t3 = -3.1 + 6.2 * k as f64 / 399.0;
            for i in 0..2000 {
                let (x0, x1) = (-3.14 + 6.28 * i as f64 / 2000.0, -3.14 + 6.28 * (i + 1) as f64 / 2000.0);
                if det(x0, t3).signum() != det(x1, t3).signum() {
                    singular.push((0.5 * (x0 + x1), t3));
                }
            }
        }
        let mut seen_regions = std::collections::BTreeSet::new();
        for (t2, t3) in [(0.0, 0.0), (1.0, 2.0), (-2.0, 0.5), (3.0, -3.0), (-0.7, -1.9)] {
            let c = a.classify(&[0.0, t2, t3], None, Some(&r)).expect("classifies");
            let bound = c.singular_distance.expect("known");
            let sampled = singular.iter().map(|&(x, y)| (gap(t2, [x, x], true).powi(2) + gap(t3, [y, y], true).powi(2)).sqrt()).fold(f64::INFINITY, f64::min);
            // The samples sit within 0.002 of the curve.
            assert!(bound <= sampled + 0.002, "({t2}, {t3}): bound {bound} above the sampled distance {sampled}");
            if let Some(k) = c.component {
                seen_regions.insert(k);
                assert!(bound > 0.0);
            }
            assert!(c.inside && c.components >= 2);
        }
        assert!(!seen_regions.is_empty());
    }

    /// Test idea: the node honours the file's joint limits as `ik` and `singularities` do.
    /// PUMA 560 limits joint 2 to [-3.927, 0.7854] and joint 3 to [-0.7854, 3.927]: on the
    /// circle, θ₂ in (0.7854, 2.3562) and θ₃ in (-2.3562, -0.7854) are out of reach. The same
    /// arm with continuous joints answers a superset; what the limited one leaves out is
    /// exactly the solutions in those arcs (checked against the decimal limits, not the
    /// library's filter), and some point must lose one.
    #[test]
    fn joint_limits_filter_what_the_node_answers() {
        const PUMA: &str = include_str!("../../urdf/puma560.urdf");
        let limited = load(&urdf::parse(PUMA).expect("bundled"), &[], &[]).expect("puma");
        let free = load(&urdf::parse(&PUMA.replace("type=\"revolute\"", "type=\"continuous\"")).expect("continuous"), &[], &[]).expect("puma");
        let tau = std::f64::consts::TAU;
        let outside = |j: &[Bounds]| (j[1][0] > 0.7854 && j[1][1] < -3.927 + tau) || (j[2][0] > 3.927 - tau && j[2][1] < -0.7854);
        let mut dropped = 0;
        for point in [[0.5, 0.0, 0.3], [0.4, 0.2, 0.6], [0.3, -0.3, 0.9], [0.6, 0.1, 0.2], [0.2, 0.2, 0.2]] {
            let q = IkQuery { point, precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 };
            let l = limited.inverse_kinematics(&q).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
            let f = free.inverse_kinematics(&q).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
            assert!(l.status.is_complete() && f.status.is_complete());
            for s in &l.solutions {
                assert!(f.solutions.iter().any(|t| t.joints == s.joints), "{point:?}: {s:?} is not a solution of the free arm");
                assert!(!outside(&s.joints), "{point:?}: {s:?} is outside the limits");
            }
            for t in f.solutions.iter().filter(|t| !l.solutions.iter().any(|s| s.joints == t.joints)) {
                assert!(outside(&t.joints), "{point:?}: {t:?} was dropped but lies within the limits");
                dropped += 1;
            }
        }
        assert!(dropped > 0, "no point lost a solution to the limits");
        let r = limited.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert!(r.summary.contains("results outside dropped"), "{}", r.summary);
        let r = free.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert!(!r.summary.contains("results outside dropped"), "{}", r.summary);
    }

    #[test]
    fn inverse_kinematics_matches_the_cli_search_and_reaches_the_point() {
        let m = urdf::parse(E).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        let chain = Chain3R::from_mechanism(&m, 0.0).expect("3R");
        let (r, z) = (1.9, 0.4);
        let reference = ik::solve(&chain, r, z, 1e-8, 200_000).expect("valid");
        // The same (ρ, z) seen from a point turned by 0.7 rad about the first axis.
        let p = [r * 0.7f64.cos(), r * 0.7f64.sin(), z];
        let got = a.inverse_kinematics(&IkQuery { point: p, precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(got.joint_names, vec!["joint1", "joint2", "joint3"]);
        assert_eq!(got.solutions.iter().filter(|s| s.unique).count(), reference.unique.len());
        assert!(reference.unique.len() >= 2);
        for s in got.solutions.iter().filter(|s| s.unique) {
            let q: Vec<f64> = s.joints.iter().map(|b| 0.5 * (b[0] + b[1])).collect();
            let tip = forward(&m, &q);
            let miss = ((tip[0] - p[0]).powi(2) + (tip[1] - p[1]).powi(2) + (tip[2] - p[2]).powi(2)).sqrt();
            assert!(miss < 1e-6, "{q:?} reaches {tip:?}, not {p:?}");
            assert!(s.joints[0][1] - s.joints[0][0] < 1e-6, "θ1 enclosed tightly: {:?}", s.joints[0]);
        }
        // On the point (r, 0, z) the boxes are the CLI's, bit for bit.
        let got = a.inverse_kinematics(&IkQuery { point: [r, 0.0, z], precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        for (s, u) in got.solutions.iter().zip(&reference.unique) {
            assert_eq!(s.joints[1..], [bounds(u[0]), bounds(u[1])]);
        }
    }

    #[test]
    fn robot_f_reports_its_internal_motions_and_bad_queries_are_refused() {
        let m = urdf::parse(F).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        let r = a.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(r.internal_motions.boxes.len(), 2);
        assert!(r.nodes.is_empty());
        let err = |e: AnalysisError| e.to_string();
        assert!(err(a.singularities(&SingularityQuery { precision: 2.0, ..query() }).err().expect("refused")).contains("precision must be a number in (0, 1), got 2"));
        let ik = |point: [f64; 3], precision: f64| a.inverse_kinematics(&IkQuery { point, precision, max_boxes: 1000, timeout: None, threads: 1 }).err().map(err).unwrap_or_default();
        assert!(ik([f64::NAN, 0.0, 0.0], 1e-6).contains("is not finite"));
        assert!(ik([1.0, 0.0, 0.0], 0.0).contains("precision must be a number in (0, 1)"));
        // A tight box limit ends incomplete, with its pending boxes as clusters.
        let short = a.inverse_kinematics(&IkQuery { point: [1.0, 0.0, 0.2], precision: 1e-9, max_boxes: 5, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert!(short.status == Status::Incomplete(Limit::Boxes) && short.solutions.iter().any(|s| !s.unique));
        // A timeout stops it too (the node passes its --max-wait, past which no reply is sent).
        let late = a.inverse_kinematics(&IkQuery { point: [1.0, 0.0, 0.2], precision: 1e-9, max_boxes: 1_000_000, timeout: Some(std::time::Duration::ZERO), threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(late.status, Status::Incomplete(Limit::Time));
        // 3R chains take no fixed joints.
        assert!(load(&m, &[("joint2".into(), 0.1)], &[]).err().map(err).unwrap_or_default().contains("takes no fixed joints"));
    }

    #[test]
    fn directions_are_enclosed() {
        for k in 0..64 {
            let angle = -3.14 + 6.28 * k as f64 / 63.0;
            let (x, y) = (2.0 * angle.cos(), 2.0 * angle.sin());
            let d = direction(interval(x - 1e-3, x + 1e-3), interval(y - 1e-3, y + 1e-3)).expect("away from 0");
            let shifted = [0.0, std::f64::consts::TAU, -std::f64::consts::TAU].iter().any(|s| d.contains(angle + s));
            assert!(shifted && d.wid() < 2e-3, "{angle}: {d:?}");
        }
        assert!(direction(interval(-1.0, 1.0), interval(-1.0, 1.0)).is_none());
    }
}

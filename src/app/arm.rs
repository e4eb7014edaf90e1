//! Serial arms: the 3R positioning structure of a robot description, and the jobs run on it
//! (singularities with the cuspidality verdict, inverse kinematics, collision sets).
//!
//! An `Arm` is read once (`arm3r::prepare`: rounding policy, chain and point, joint limits);
//! each job takes it with the front end's `Control` and returns what happened as values. The
//! CLI prints and writes the JSON reports (`report::manip3r`) from these results; the ROS node
//! converts the same results into its messages.

use crate::analyses::arm3r::{
    self,
    branches::{Attribution, SingularBranches},
    collision::{self, CollisionSet, CollisionSettings, Scene},
    frame::{BaseFrame, Target},
    ik::IkSolutions,
    limits::LimitEffect,
    verdict::{self, Verdict},
    Chain3R, LoadOptions, Manip3rError, Prepared, Singularities,
};
use crate::model::Mechanism;
use crate::kernel::search::{Control, Progress};
use inari::Interval;
use std::time::Instant;



/// A serial arm as the 3R analyses read it.
#[derive(Clone, Debug)]
pub struct Arm {
    /// The reduced serial mechanism, what was chosen and changed, and the joint limits.
    pub prepared: Prepared,
    /// The half-section map of the positioning structure.
    pub chain: Chain3R,
    /// Where the chain sits in the robot's root frame.
    pub frame: BaseFrame,
    /// The certified singular branches of an arm whose axes 2 and 3 are parallel.
    pub branches: Option<SingularBranches>,
}

impl Arm {
    /// Reads the arm of `mechanism` as `options` say, every length widened by `uncertainty`
    /// metres (0 for the nominal geometry).
    pub fn load(mechanism: &Mechanism, options: &LoadOptions, uncertainty: f64) -> Result<Self, Manip3rError> {
        let prepared = arm3r::prepare(mechanism, options)?;
        // The chain names its point by the reduced mechanism's link, made up for a joint's origin.
        let chain = Chain3R::from_mechanism(&prepared.mechanism, uncertainty).map_err(|e| match (e, prepared.choice.origin_text()) {
            (Manip3rError::TipDoesNotMove(_), Some(point)) => Manip3rError::TipDoesNotMove(point),
            (Manip3rError::Degenerate(_), Some(point)) => Manip3rError::Degenerate(point),
            (e, _) => e,
        })?;
        let frame = BaseFrame::of(&prepared.mechanism, &chain);
        let branches = arm3r::branches::of(&prepared.mechanism, &chain);
        Ok(Self { prepared, chain, frame, branches })
    }
}

/// What a singularity run is asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingularitiesRequest {
    /// Largest width (radians) of reported and undecided boxes, in (0, 1).
    pub precision: f64,
    /// Also search nodes (pairs of singular points with one image).
    pub nodes: bool,
    /// Run the interval searches even where the verdict is structural (axes 2 and 3 parallel),
    /// where they cannot complete.
    pub search_anyway: bool,
    /// Decide the cuspidality verdict (with its aspects and IK counts) after the searches;
    /// false for the searches alone.
    pub verdict: bool,
}

/// Cusps, nodes, internal motions and the verdict of one arm.
#[derive(Clone, Debug)]
pub struct ArmSingularities {
    /// What was asked.
    pub request: SingularitiesRequest,
    /// The searches' results inside the joint limits (the verdict reads the full torus).
    pub run: Singularities,
    /// The first answer: cuspidal or not, with its argument (`None` when not asked).
    pub verdict: Option<Verdict>,
    /// What the joint limits removed.
    pub limit_effect: LimitEffect,
    /// Axes 2 and 3 parallel, nominal geometry, searches not forced: the cusp answer comes from
    /// the verdict's proof and the interval searches were not run.
    pub structural: bool,
    /// Whether the node search ran (it is not run where the singular branches are curves of
    /// nodes).
    pub nodes_searched: bool,
    /// Where the cusp search's undecided boxes lie relative to the singular branches.
    pub explained: Option<Attribution>,
    /// Searches not run, and why.
    pub not_searched: Option<String>,
    /// Wall-clock seconds of the searches and the verdict.
    pub seconds: f64,
}

/// Cusps, then nodes, then the verdict, within one `control` (one deadline for all).
pub fn singularities(arm: &Arm, request: &SingularitiesRequest, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<ArmSingularities, Manip3rError> {
    arm3r::check_precision(request.precision)?;
    let (chain, mechanism) = (&arm.chain, &arm.prepared.mechanism);
    let structural = chain.uncertainty == 0.0 && !request.search_anyway && verdict::parallel_structure(mechanism).is_some();
    // On arms with known singular branches whole branches are curves of nodes: the isolated-node
    // search floods, so it is not run even when the searches are forced.
    let nodes_searched = request.nodes && arm.branches.is_none();
    let start = Instant::now();
    let mut run = if structural {
        arm3r::structural_singularities(chain, request.precision, control)?
    } else {
        arm3r::singularities(chain, request.precision, nodes_searched, control, progress)?
    };
    // The verdict reads the full-torus run; the limits then filter what is listed.
    let verdict = request.verdict.then(|| {
        let mut verdict = verdict::decide(mechanism, chain, &run, &arm.prepared.limits, &control.remaining_since(start));
        // An undecided verdict says what blocks it (not for uncertain lengths, nor for certified
        // cusps outside the limits: those reasons say what to do).
        if verdict.cuspidal.is_none() && chain.uncertainty == 0.0 && !run.cusps.cusps.iter().any(|c| c.unique) {
            verdict.reason.push_str(&verdict::blockers(&arm.prepared, chain, request.precision, &control.remaining_since(start)));
        }
        verdict
    });
    let limit_effect = arm.prepared.limits.apply(&mut run);
    let mut explained = None;
    let mut not_searched = None;
    if let Some(b) = &arm.branches {
        if !structural {
            let boxes: Vec<[Interval; 2]> = run.cusps.undecided.iter().map(|u| u.theta).chain(run.cusps.cusps.iter().filter(|c| !c.unique).map(|c| c.theta)).collect();
            if !boxes.is_empty() {
                explained = Some(b.attribute(mechanism, &boxes, 1e-2));
            }
            if request.nodes {
                not_searched = Some("nodes not enumerated: the singular branches are curves of nodes (see the singular branches), which the isolated-node search does not model".to_string());
            }
        }
    }
    if structural {
        not_searched = Some(format!(
            "axes 2 and 3 are parallel: no cusp point, by the verdict's proof; {} (--search-anyway runs the interval searches, which cannot complete here)",
            if request.nodes { "nodes not enumerated: the singular branches cross and map onto shared curves (curves of nodes), which the isolated-node search does not model" } else { "nodes not asked" }
        ));
    }
    Ok(ArmSingularities { request: *request, run, verdict, limit_effect, structural, nodes_searched, explained, not_searched, seconds: start.elapsed().as_secs_f64() })
}

/// A point asked of inverse kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkPoint {
    /// A point of the robot's root frame (metres): every joint of the chain is solved for.
    Root([f64; 3]),
    /// Half-section coordinates in the first joint's frame: distance from the first axis and
    /// height along it (metres). The first joint is free (any angle turns the point about the
    /// axis), so only joints 2 and 3 are solved for.
    HalfSection {
        /// Distance from the first axis.
        radius: f64,
        /// Height along the first axis.
        z: f64,
    },
}

/// Every solution of one inverse-kinematics query.
#[derive(Clone, Debug)]
pub struct ArmIk {
    /// The point asked.
    pub point: IkPoint,
    /// The point as the search took it (`None` for a half-section point, taken exactly).
    pub target: Option<Target>,
    /// Solutions over (θ₂, θ₃) inside the joint limits: unique boxes, then clusters.
    pub solutions: IkSolutions,
    /// What the joint limits removed.
    pub limit_effect: LimitEffect,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Every joint solution of `arm` reaching `point`, within `control`.
pub fn inverse_kinematics(arm: &Arm, point: IkPoint, precision: f64, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<ArmIk, Manip3rError> {
    let start = Instant::now();
    let (mut solutions, target): (_, Option<Target>) = match point {
        IkPoint::HalfSection { radius, z } => (arm3r::ik::solve_with(&arm.chain, radius, z, precision, control, progress)?, None),
        IkPoint::Root(p) => {
            if p.iter().any(|v| !v.is_finite()) {
                return Err(Manip3rError::BadTarget(p));
            }
            let target = arm.frame.target(p);
            (arm3r::ik::solve_target(&arm.chain, target.half_section, precision, control, progress)?, Some(target))
        }
    };
    // Solutions outside the file's joint limits are not solutions of the arm; those on a limit
    // are kept.
    let limit_effect = arm.prepared.limits.apply_ik(&mut solutions, |b| target.map(|t| arm.frame.theta1(&arm.chain, &t, b)));
    Ok(ArmIk { point, target, solutions, limit_effect, seconds: start.elapsed().as_secs_f64() })
}

impl ArmSingularities {
    /// Lines of internal motions the cusp search found.
    pub fn internal_motion_lines(&self) -> usize {
        arm3r::line_count(&self.run.cusps.bands)
    }

    /// The one rule over the searches: the limit that stopped one, else near-degenerate strips,
    /// else undecided boxes and pairs (cusps without a uniqueness proof among them).
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        let (cusps, nodes) = (&self.run.cusps, self.run.nodes.as_ref());
        let status = nodes.map_or(cusps.status, |n| cusps.status.and(n.status));
        let undecided = cusps.undecided.len() + cusps.cusps.iter().filter(|c| !c.unique).count() + nodes.map_or(0, |n| n.undecided.len());
        let near = cusps.bands.iter().any(|b| b.near.is_some());
        crate::kernel::outcome::Completeness::of(status, undecided, near)
    }
}

impl ArmIk {
    /// The first joint's angle for a solution box over (θ₂, θ₃), in the joint's range: `None`
    /// for a half-section point (θ₁ is free), the whole turn where the point or the end point
    /// may lie on the first axis.
    pub fn theta1(&self, arm: &Arm, b: &[Interval; 2]) -> Option<Interval> {
        self.target.map(|t| arm.prepared.limits.in_range(0, arm.frame.theta1(&arm.chain, &t, b)))
    }
}

/// Where the collision capsules of an arm meet, over (θ₂, θ₃).
#[derive(Clone, Debug)]
pub struct ArmCollisions {
    /// The reduced arm, as read.
    pub prepared: Prepared,
    /// Its capsules and the pairs checked.
    pub scene: Scene,
    /// Colliding, free and undecided boxes.
    pub set: CollisionSet,
}

impl ArmCollisions {
    /// The classification in one line, as the CLI prints it (before its time) and the node's reply
    /// says it: the pairs, and the boxes of each kind with their share of the joint space.
    pub fn headline(&self) -> String {
        let (scene, set) = (&self.scene, &self.set);
        let total = set.colliding_area + set.free_area + set.undecided_area;
        let share = |area: f64| if total > 0.0 { 100.0 * area / total } else { 0.0 };
        format!(
            "{}: {} pairs; colliding {} boxes ({:.2} % of joint space), free {} ({:.2} %), undecided {} ({:.2} %), status {}",
            scene.name,
            scene.pairs().len(),
            set.colliding.len(),
            share(set.colliding_area),
            set.free.len(),
            share(set.free_area),
            set.undecided.len(),
            share(set.undecided_area),
            set.completeness().text()
        )
    }
}

/// The collision set of the arm of `mechanism` (read as `options` say), within `control`.
///
/// Takes the mechanism rather than an `Arm`: collisions need the capsules of the chosen chain,
/// not its half-section map, which may be degenerate where collisions are still well defined.
pub fn collisions(mechanism: &Mechanism, options: &LoadOptions, precision: f64, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<ArmCollisions, Manip3rError> {
    arm3r::check_precision(precision)?;
    let prepared = arm3r::prepare(mechanism, options)?;
    let scene = Scene::from_mechanism(&prepared.mechanism)?;
    let set = collision::classify_with(&scene, &CollisionSettings { precision }, control, progress)?;
    Ok(ArmCollisions { prepared, scene, set })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::*;
    use crate::kernel::interval::bounds;
    use std::sync::atomic::AtomicBool;
    use crate::kernel::interval::{point, Bounds};
    use crate::analyses::arm3r::ik;
    use crate::app::load;
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
    #[allow(clippy::approx_constant)] // a sample grid over [-3.14, 3.14], not π
    fn robot_e_has_the_table_counts_and_a_sound_curve_cover() {
        let m = urdf::parse(E).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        assert_eq!(a.kind(), MechanismKind::Manipulator3R);
        let r = a.singularities(&query()).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert_eq!(r.status, Status::Finished);
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
    #[allow(clippy::approx_constant)] // a sample grid over [-3.14, 3.14], not π
    fn classification_gives_a_sound_lower_bound_on_the_singular_distance() {
        let m = urdf::parse(E).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        let chain = Chain3R::from_mechanism(&m, 0.0).expect("3R");
        // A cusp's own configuration is singular: distance 0, no region.
        let r = a.singularities(&query()).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
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
    /// PUMA 560 limits joint 1 to [-2.7925, 2.7925], joint 2 to [-3.927, 0.7854] and joint 3 to
    /// [-0.7854, 3.927]: on the circle, θ₁ beyond ±2.7925, θ₂ in (0.7854, 2.3562) and θ₃ in
    /// (-2.3562, -0.7854) are out of reach (θ₁ is fixed by the point, so its limits count). The same
    /// arm with continuous joints answers a superset; what the limited one leaves out is
    /// exactly the solutions in those arcs (checked against the decimal limits, not the
    /// library's filter), and some point must lose one.
    #[test]
    #[allow(clippy::approx_constant)] // the decimal limits of puma560.urdf, not π/4
    fn joint_limits_filter_what_the_node_answers() {
        const PUMA: &str = include_str!("../../urdf/puma560.urdf");
        let limited = load(&urdf::parse(PUMA).expect("bundled"), &[], &[]).expect("puma");
        let free = load(&urdf::parse(&PUMA.replace("type=\"revolute\"", "type=\"continuous\"")).expect("continuous"), &[], &[]).expect("puma");
        let tau = std::f64::consts::TAU;
        let outside = |j: &[Bounds]| (j[0][0] > 2.7925 && j[0][1] < -2.7925 + tau) || (j[0][1] < -2.7925 && j[0][0] > 2.7925 - tau) || (j[1][0] > 0.7854 && j[1][1] < -3.927 + tau) || (j[2][0] > 3.927 - tau && j[2][1] < -0.7854);
        // The limited arm states its angles in the joints' ranges: the same solution up to turns.
        let same = |a: &[Bounds], b: &[Bounds]| {
            a.iter().zip(b).all(|(x, y)| {
                let turns = ((x[0] - y[0]) / tau).round() * tau;
                (x[0] - y[0] - turns).abs() < 1e-9 && (x[1] - y[1] - turns).abs() < 1e-9
            })
        };
        let mut dropped = 0;
        for point in [[0.5, 0.0, 0.3], [0.4, 0.2, 0.6], [0.3, -0.3, 0.9], [0.6, 0.1, 0.2], [0.2, 0.2, 0.2]] {
            let q = IkQuery { point, precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 };
            let l = limited.inverse_kinematics(&q).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
            let f = free.inverse_kinematics(&q).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
            assert!(l.status.finished() && f.status.finished());
            for s in &l.solutions {
                assert!(f.solutions.iter().any(|t| same(&t.joints, &s.joints)), "{point:?}: {s:?} is not a solution of the free arm");
                assert!(!outside(&s.joints), "{point:?}: {s:?} is outside the limits");
            }
            for t in f.solutions.iter().filter(|t| !l.solutions.iter().any(|s| same(&s.joints, &t.joints))) {
                assert!(outside(&t.joints), "{point:?}: {t:?} was dropped but lies within the limits");
                dropped += 1;
            }
        }
        assert!(dropped > 0, "no point lost a solution to the limits");
        let r = limited.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert!(r.summary.contains("results outside dropped"), "{}", r.summary);
        let r = free.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
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
        let got = a.inverse_kinematics(&IkQuery { point: p, precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
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
        let got = a.inverse_kinematics(&IkQuery { point: [r, 0.0, z], precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        for (s, u) in got.solutions.iter().zip(&reference.unique) {
            assert_eq!(s.joints[1..], [bounds(u[0]), bounds(u[1])]);
        }
    }

    #[test]
    fn robot_f_reports_its_internal_motions_and_bad_queries_are_refused() {
        let m = urdf::parse(F).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        let r = a.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert_eq!(r.internal_motions.boxes.len(), 2);
        assert!(r.nodes.is_empty());
        let err = |e: crate::app::JobError| e.to_string();
        assert!(err(a.singularities(&SingularityQuery { precision: 2.0, ..query() }).err().expect("refused")).contains("precision must be a number in (0, 1), got 2"));
        let ik = |point: [f64; 3], precision: f64| a.inverse_kinematics(&IkQuery { point, precision, max_boxes: 1000, timeout: None, threads: 1 }).err().map(err).unwrap_or_default();
        assert!(ik([f64::NAN, 0.0, 0.0], 1e-6).contains("is not finite"));
        assert!(ik([1.0, 0.0, 0.0], 0.0).contains("precision must be a number in (0, 1)"));
        // A tight box limit ends incomplete, with its pending boxes as clusters.
        let short = a.inverse_kinematics(&IkQuery { point: [1.0, 0.0, 0.2], precision: 1e-9, max_boxes: 5, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert!(short.status == Status::Stopped(Limit::Boxes) && short.solutions.iter().any(|s| !s.unique));
        // A timeout stops it too (the node passes its --max-wait, past which no reply is sent).
        let late = a.inverse_kinematics(&IkQuery { point: [1.0, 0.0, 0.2], precision: 1e-9, max_boxes: 1_000_000, timeout: Some(std::time::Duration::ZERO), threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert_eq!(late.status, Status::Stopped(Limit::Time));
        // 3R chains take no fixed joints.
        assert!(load(&m, &[("joint2".into(), 0.1)], &[]).err().map(|e| e.to_string()).unwrap_or_default().contains("takes no fixed joints"));
    }
}

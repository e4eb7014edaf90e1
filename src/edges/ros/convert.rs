//! From the analysis layer's plain results to wire types: box sets, markers, joint states.

use super::msgs::{
    self, AssemblyMode, BoxSet, CollisionsResponse, SelfMotionResponse, ColorRGBA, CuspRecord, Header, Ik6Solutions, InverseKinematics6Response, InverseKinematicsResponse, JointState, PathCheckResponse, LsBox, Marker, MarkerArray, NodeRecord, Point, Pose, Quaternion, SingularityReport,
    SolveStats, TfMessage, Time, Transform, TransformStamped, Vector3,
};
use crate::app::{joints_over, ArmCollisions, ArmIk6, ArmPathCheck, Bounds, BoxSetResult, Chain6R, IkResult, ResultBox, SegmentVerdict, SingularBranches, SingularityResult, SolverSettings};
use crate::kernel::outcome::{BoxStatus, Completeness, Incompleteness, Status};

/// A header stamped now (wall clock) in `frame`.
pub(crate) fn header(frame: &str) -> Header {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
    Header { stamp: Time { sec: now.as_secs().min(i32::MAX as u64) as i32, nanosec: now.subsec_nanos() }, frame_id: frame.to_string() }
}

/// The wire form of the settings (`timeout` 0 for none).
pub(crate) fn settings(s: &SolverSettings) -> msgs::Settings {
    msgs::Settings { sigma: s.sigma, rho: s.rho, max_boxes: s.max_boxes, timeout: s.timeout.map_or(0.0, |t| t.as_secs_f64()) }
}

/// The wire value of a box's status (`Box.SOLUTION`, `Box.UNIQUE`, `Box.UNDECIDED`).
pub(crate) fn box_status(s: BoxStatus) -> u8 {
    match s {
        BoxStatus::Solution => msgs::BOX_SOLUTION,
        BoxStatus::Unique => msgs::BOX_UNIQUE,
        BoxStatus::Undecided => msgs::BOX_UNDECIDED,
    }
}

/// A result as a `linkspace_msgs/BoxSet`, boxes in the result's order, in frame
/// `<robot>/joint_space`.
pub(crate) fn box_set(r: &BoxSetResult, run_id: u64) -> BoxSet {
    let n = r.boxes.len();
    let (mut lower, mut upper) = (Vec::with_capacity(n * r.variables.len()), Vec::with_capacity(n * r.variables.len()));
    let (mut joint_lower, mut joint_upper) = (Vec::with_capacity(n * r.joint_names.len()), Vec::with_capacity(n * r.joint_names.len()));
    for b in &r.boxes {
        lower.extend(b.bounds.iter().map(|x| x[0]));
        upper.extend(b.bounds.iter().map(|x| x[1]));
        joint_lower.extend(b.joints.iter().map(|x| x[0]));
        joint_upper.extend(b.joints.iter().map(|x| x[1]));
    }
    // Complete means nothing undecided, as in the CLI's reports.
    let (status, limit) = match r.completeness().reason() {
        None => (msgs::SET_COMPLETE, ""),
        Some(why) => (msgs::SET_INCOMPLETE, why.name()),
    };
    BoxSet {
        header: header(&joint_frame(&r.mechanism)),
        mechanism: r.mechanism.clone(),
        analysis: r.analysis.clone(),
        run_id,
        status,
        limit: limit.to_string(),
        settings: settings(&r.settings),
        variable_names: r.variables.clone(),
        dim: r.variables.len() as u32,
        lower,
        upper,
        box_status: r.boxes.iter().map(|b| box_status(b.status)).collect(),
        level: r.boxes.iter().map(|b| b.level).collect(),
        cluster: r.boxes.iter().map(|b| b.cluster.map_or(-1, |c| c as i32)).collect(),
        clusters: r.clusters as u32,
        joint_names: r.joint_names.clone(),
        joint_lower,
        joint_upper,
        fixed_joint_names: r.fixed_joints.iter().map(|(n, _)| n.clone()).collect(),
        fixed_joint_values: r.fixed_joints.iter().map(|(_, v)| *v).collect(),
        stats: SolveStats {
            processed: r.stats.processed,
            empty: r.stats.empty,
            bisected: r.stats.bisected,
            solutions: r.stats.solutions,
            spurious_dropped: r.stats.spurious_dropped,
            max_level: r.stats.max_level,
            seconds: r.stats.seconds,
            certified: r.stats.certified,
            post_processing_cut_short: r.stats.post_processing_cut_short,
        },
        merged_from: 0,
    }
}

/// A colour per cluster, cycling through a few distinct hues; undecided boxes are grey.
fn colour(cluster: Option<usize>) -> ColorRGBA {
    const HUES: [(f32, f32, f32); 6] = [(0.12, 0.47, 0.71), (1.0, 0.5, 0.05), (0.17, 0.63, 0.17), (0.84, 0.15, 0.16), (0.58, 0.4, 0.74), (0.55, 0.34, 0.29)];
    match cluster {
        Some(c) => {
            let (r, g, b) = HUES[c % HUES.len()];
            ColorRGBA { r, g, b, a: 0.8 }
        }
        None => ColorRGBA { r: 0.5, g: 0.5, b: 0.5, a: 0.3 },
    }
}

fn cube(frame: &str, ns: &str, id: i32, centre: [f64; 3], size: [f64; 3], color: ColorRGBA) -> Marker {
    Marker {
        header: header(frame),
        ns: ns.to_string(),
        id,
        r#type: msgs::marker::CUBE,
        action: msgs::marker::ADD,
        pose: Pose { position: Point { x: centre[0], y: centre[1], z: centre[2] }, orientation: Quaternion { w: 1.0, ..Default::default() } },
        // RViz does not draw a cube of zero size: give flat boxes a sliver of thickness.
        scale: Vector3 { x: size[0].max(1e-4), y: size[1].max(1e-4), z: size[2].max(1e-4) },
        color,
        ..Default::default()
    }
}

/// Markers for RViz: a `DELETEALL` first (a new result replaces the old one), then
/// - namespace `configuration_space`: one cube per box over the first three free joints
///   (radians or metres as metres), in frame `<robot>/joint_space`;
/// - namespace `trace:<LINK@X,Y>`: one flat cube per box for each traced point (a coupler
///   curve), in the world frame `world_frame`.
///
/// At most `cap` boxes are drawn per namespace (the box-set topic always carries all of them).
pub(crate) fn markers(r: &BoxSetResult, world_frame: &str, cap: usize) -> MarkerArray {
    let mut markers = vec![Marker { header: header(world_frame), action: msgs::marker::DELETEALL, ..Default::default() }];
    let joint_frame = joint_frame(&r.mechanism);
    let axes = r.joint_names.len().min(3);
    let mut id = 0;
    for b in r.boxes.iter().take(cap) {
        let (mut c, mut s) = ([0.0; 3], [0.0; 3]);
        for k in 0..axes {
            c[k] = 0.5 * (b.joints[k][0] + b.joints[k][1]);
            s[k] = b.joints[k][1] - b.joints[k][0];
        }
        markers.push(cube(&joint_frame, "configuration_space", id, c, s, colour(b.cluster)));
        id += 1;
    }
    for (t, name) in r.traces.iter().enumerate() {
        let ns = format!("trace:{name}");
        for b in r.boxes.iter().take(cap) {
            let (x, y) = (b.traces[t].x, b.traces[t].y);
            let c = [0.5 * (x[0] + x[1]), 0.5 * (y[0] + y[1]), 0.0];
            markers.push(cube(world_frame, &ns, id, c, [x[1] - x[0], y[1] - y[0], 0.0], colour(b.cluster)));
            id += 1;
        }
    }
    MarkerArray { markers }
}

/// One `sensor_msgs/JointState` per isolated solution (assembly mode), in cluster order, in
/// frame `root_link`, with its `linkspace_msgs/AssemblyMode` (the same configuration with its
/// index, count and cluster, and the same stamp). The names cover the free joints (loop joints
/// included) and the fixed ones; values in REP-103 units (radians and metres), as the analyses
/// give joint space.
pub(crate) fn assembly_modes(r: &BoxSetResult, run_id: u64, root_link: &str) -> Vec<(JointState, AssemblyMode)> {
    let modes = r.assembly_modes();
    let n = modes.len();
    let h = header(root_link);
    modes
        .into_iter()
        .enumerate()
        .map(|(k, m)| {
            let name: Vec<String> = m.joints.iter().map(|(j, _)| j.clone()).collect();
            let position: Vec<f64> = m.joints.iter().map(|&(_, v)| v).collect();
            let js = JointState { header: h.clone(), name: name.clone(), position: position.clone(), velocity: vec![], effort: vec![] };
            let mode = AssemblyMode {
                header: h.clone(),
                mechanism: r.mechanism.clone(),
                run_id,
                mode: k as u32,
                modes: n as u32,
                cluster: m.cluster as i32,
                joint_names: name,
                positions: position,
            };
            (js, mode)
        })
        .collect()
}

fn intervals(b: &[Bounds]) -> Vec<msgs::Interval> {
    b.iter().map(|x| msgs::Interval { lower: x[0], upper: x[1] }).collect()
}

/// A singularity result as a `linkspace_msgs/SingularityReport`, records in the result's order.
pub(crate) fn singularity_report(r: &SingularityResult, run_id: u64) -> SingularityReport {
    let limit = r.completeness().reason();
    SingularityReport {
        header: header(&joint_frame(&r.mechanism)),
        mechanism: r.mechanism.clone(),
        run_id,
        ok: true,
        message: r.summary.clone(),
        singular_curves: box_set(&r.singular_curves, run_id),
        cusps: r.cusps.iter().map(|c| CuspRecord { joints: intervals(&c.joints), workspace: intervals(&c.workspace), certified: c.certified }).collect(),
        nodes: r
            .nodes
            .iter()
            .map(|n| NodeRecord { joints_a: intervals(&n.joints[0]), joints_b: intervals(&n.joints[1]), workspace: intervals(&n.workspace), certified: n.certified })
            .collect(),
        internal_motions: box_set(&r.internal_motions, run_id),
        joint_names: r.joint_names.clone(),
        workspace_names: r.workspace_names.clone(),
        // Complete means nothing undecided: the CLI report's rule, one function.
        complete: limit.is_none(),
        precision: r.query.precision,
        limit: limit.map_or("", Incompleteness::name).to_string(),
        set_kinds: r.loops.iter().flat_map(|l| &l.sets).map(|s| s.kind.to_string()).collect(),
        sets: r.loops.iter().flat_map(|l| &l.sets).map(|s| box_set(&s.boxes, run_id)).collect(),
        set_proven: r.loops.iter().flat_map(|l| &l.sets).map(|s| s.proven.min(u32::MAX as usize) as u32).collect(),
        set_undecided: r.loops.iter().flat_map(|l| &l.sets).map(|s| s.undecided.min(u32::MAX as usize) as u32).collect(),
        set_verdicts: r.loops.iter().flat_map(|l| &l.sets).map(|s| s.summary.clone()).collect(),
        actuated: r.loops.as_ref().map_or_else(Vec::new, |l| l.actuated.clone()),
        actuated_source: r.loops.as_ref().map_or_else(String::new, |l| l.actuated_source.clone()),
        arm_cuspidality: r.arm_cuspidality.as_ref().map_or_else(String::new, |a| a.verdict.name().to_string()),
        arm_cuspidality_reason: r.arm_cuspidality.as_ref().map_or_else(String::new, |a| a.reason.clone()),
        ..verdict_and_branches(r, run_id)
    }
}

/// An empty report (a refusal's, or a mechanism without the analysis) with the verdict
/// fields at their unknown values (`cuspidal` UNKNOWN, counts -1), not the wire defaults.
pub(crate) fn no_report() -> SingularityReport {
    SingularityReport { cuspidal: msgs::UNKNOWN, aspects: -1, max_ik_solutions: -1, ..Default::default() }
}

/// `SingularityReport.YES`, `NO` or `UNKNOWN`.
pub(crate) fn tri_state(x: Option<bool>) -> i8 {
    match x {
        Some(true) => msgs::YES,
        Some(false) => msgs::NO,
        None => msgs::UNKNOWN,
    }
}

/// The appended verdict and branch fields of a singularity report (the rest default): the
/// `verdict` and `singular_branches` of `linkspace singularities --json`. Without a verdict (a
/// closed-loop mechanism) every field is unknown and the reason says why; without branches
/// (axes 2 and 3 not parallel) they are empty.
pub(crate) fn verdict_and_branches(r: &SingularityResult, run_id: u64) -> SingularityReport {
    let count = |x: Option<u32>| x.map_or(-1, |v| v.min(i32::MAX as u32) as i32);
    let mut m = match &r.verdict {
        Some(v) => SingularityReport {
            cuspidal: tri_state(v.cuspidal),
            aspects: count(v.aspects),
            max_ik_solutions: count(v.max_ik_solutions),
            verdict_certified: v.certified,
            verdict_reason: v.reason.clone(),
            ..Default::default()
        },
        None => SingularityReport {
            cuspidal: msgs::UNKNOWN,
            aspects: -1,
            max_ik_solutions: -1,
            verdict_certified: false,
            verdict_reason: "no verdict: cuspidality, aspects and IK counts are decided for 3R manipulators only".into(),
            ..Default::default()
        },
    };
    m.branch_crossings = crossing_set(r, r.branches.as_ref(), run_id);
    let Some(b) = &r.branches else { return m };
    m.branch_names = b.branches.iter().map(|x| x.name.clone()).collect();
    m.branch_kinds = b.branches.iter().map(|x| x.kind.to_string()).collect();
    m.branch_descriptions = b.branches.iter().map(|x| x.description.clone()).collect();
    m.branch_image_descriptions = b.branches.iter().map(|x| x.image.description.clone()).collect();
    m.branch_curve_of_nodes = b.branches.iter().map(|x| tri_state(x.curve_of_nodes)).collect();
    m.branch_proofs = b.branches.iter().map(|x| x.proof.clone()).collect();
    m.branch_images = b.branches.iter().flat_map(|x| intervals(&[x.image.radius, x.image.z])).collect();
    let crossings = b.distinct_crossings();
    m.crossing_names = crossings.iter().map(|(c, _)| c.name.clone()).collect();
    m.crossing_branches = crossings
        .iter()
        .flat_map(|(_, on)| {
            // Two branches cross at each crossing; u32::MAX pads a side not listed.
            let side = |k: usize| on.get(k).map_or(u32::MAX, |&i| i as u32);
            [side(0), side(1)]
        })
        .collect();
    // Isolated nodes come with the closed form's proof: certified.
    m.branch_isolated_nodes = b
        .isolated_nodes
        .iter()
        .map(|n| NodeRecord {
            joints_a: intervals(&joints_over(&n.points[0], &r.joint_names)),
            joints_b: intervals(&joints_over(&n.points[1], &r.joint_names)),
            workspace: intervals(&n.workspace.bounds()),
            certified: true,
        })
        .collect();
    m.branches_no_cusp_proven = b.no_cusp_proven;
    m.branches_argument = b.argument.clone();
    m
}

/// The crossings as a box set (analysis `branch_crossings`): variables the record joints then
/// the workspace coordinates, each box `Box.UNIQUE` (one crossing), cluster = its index.
fn crossing_set(r: &SingularityResult, b: Option<&SingularBranches>, run_id: u64) -> BoxSet {
    let crossings = b.map_or_else(Vec::new, |b| b.distinct_crossings());
    let boxes: Vec<ResultBox> = crossings
        .iter()
        .enumerate()
        .map(|(k, (c, _))| {
            let joints = joints_over(&c.joints, &r.joint_names);
            ResultBox { status: BoxStatus::Unique, bounds: joints.iter().chain(&c.workspace.bounds()).copied().collect(), joints, level: 0, cluster: Some(k), traces: vec![] }
        })
        .collect();
    let n = boxes.len();
    let set = BoxSetResult {
        mechanism: r.mechanism.clone(),
        analysis: "branch_crossings".into(),
        status: Status::Finished,
        settings: SolverSettings { sigma: r.query.precision, ..Default::default() },
        variables: r.joint_names.iter().chain(&r.workspace_names).cloned().collect(),
        primaries: (0..r.joint_names.len()).collect(),
        joint_names: r.joint_names.clone(),
        fixed_joints: vec![],
        traces: vec![],
        boxes,
        clusters: n,
        stats: crate::app::SolveStats { solutions: n as u64, certified: n as u64, ..Default::default() },
    };
    let mut out = box_set(&set, run_id);
    if b.is_some_and(|b| b.crossings.is_none()) {
        // Existence of crossings not decided everywhere: incomplete, as a run with boxes left
        // undecided.
        (out.status, out.limit) = (msgs::SET_INCOMPLETE, Incompleteness::Undecided.name().into());
    }
    out
}

fn sphere(frame: &str, ns: &str, id: i32, centre: [f64; 3], size: f64, color: ColorRGBA) -> Marker {
    Marker { r#type: msgs::marker::SPHERE, ..cube(frame, ns, id, centre, [size; 3], color) }
}

/// Markers for RViz of a singularity result, all in frame `<robot>/joint_space` over the
/// record joints (x, y; radians as metres): a `DELETEALL`, then namespace `singular_curves`
/// (one flat cube per cover box, coloured by piece), `internal_motions` (one flat cube per
/// line), `cusps` (red spheres; grey when undecided) and `nodes` (blue spheres, one per point
/// of each pair); for a linkage, `singular_set:<kind>` (one cube per box over its first three
/// free joints, red for cspace, purple for input, brown for output; grey when undecided). At
/// most `cap` markers per namespace.
pub(crate) fn singularity_markers(r: &SingularityResult, cap: usize) -> MarkerArray {
    let frame = joint_frame(&r.mechanism);
    let mut markers = vec![Marker { header: header(&frame), action: msgs::marker::DELETEALL, ..Default::default() }];
    let mut id = 0;
    let centre = |j: &[Bounds]| [0.5 * (j[0][0] + j[0][1]), 0.5 * (j[1][0] + j[1][1]), 0.0];
    let size = |j: &[Bounds]| [j[0][1] - j[0][0], j[1][1] - j[1][0], 0.0];
    for (ns, set) in [("singular_curves", &r.singular_curves), ("internal_motions", &r.internal_motions)] {
        for b in set.boxes.iter().take(cap) {
            let mut c = colour(b.cluster);
            c.a = 0.5;
            markers.push(cube(&frame, ns, id, centre(&b.joints), size(&b.joints), c));
            id += 1;
        }
    }
    let grey = ColorRGBA { r: 0.5, g: 0.5, b: 0.5, a: 0.9 };
    for c in r.cusps.iter().take(cap) {
        let red = ColorRGBA { r: 0.9, g: 0.1, b: 0.1, a: 1.0 };
        markers.push(sphere(&frame, "cusps", id, centre(&c.joints), 0.08, if c.certified { red } else { grey.clone() }));
        id += 1;
    }
    // A linkage's singular sets: one cube per box over its first three free joints (as the
    // configuration-space markers), namespace `singular_set:<kind>`, coloured by kind.
    for (k, set) in r.loops.iter().flat_map(|l| &l.sets).enumerate() {
        let ns = format!("singular_set:{}", set.kind);
        let axes = set.boxes.joint_names.len().min(3);
        for b in set.boxes.boxes.iter().take(cap) {
            let (mut c, mut s) = ([0.0; 3], [0.0; 3]);
            for i in 0..axes {
                c[i] = 0.5 * (b.joints[i][0] + b.joints[i][1]);
                s[i] = b.joints[i][1] - b.joints[i][0];
            }
            let color = if b.status == BoxStatus::Undecided { grey.clone() } else { colour(Some(3 + k)) };
            markers.push(cube(&frame, &ns, id, c, s, color));
            id += 1;
        }
    }
    for n in r.nodes.iter().take(cap) {
        let blue = ColorRGBA { r: 0.1, g: 0.2, b: 0.9, a: 1.0 };
        for point in &n.joints {
            markers.push(sphere(&frame, "nodes", id, centre(point), 0.08, if n.certified { blue.clone() } else { grey.clone() }));
            id += 1;
        }
    }
    MarkerArray { markers }
}

/// The reply to an inverse-kinematics request.
pub(crate) fn ik_response(r: &IkResult) -> InverseKinematicsResponse {
    let unique = r.solutions.iter().filter(|s| s.unique).count();
    let clusters = r.solutions.len() - unique;
    let mut message = format!("{unique} solutions proven unique, {clusters} clusters undecided at sigma (each may hold one or several solutions, or a line of them)");
    if let crate::app::Status::Stopped(limit) = r.status {
        message.push_str(&format!("; incomplete ({} limit): the clusters include the boxes left pending", limit.name()));
    }
    InverseKinematicsResponse {
        ok: true,
        message,
        complete: r.status.finished(),
        solutions: r
            .solutions
            .iter()
            .enumerate()
            .map(|(k, s)| LsBox { intervals: intervals(&s.joints), status: msgs::BOX_SOLUTION, level: 0, cluster: k as i32 })
            .collect(),
        joint_names: r.joint_names.clone(),
        unique: r.solutions.iter().map(|s| s.unique).collect(),
        merged_boxes: r.solutions.iter().map(|s| s.boxes.min(u32::MAX as usize) as u32).collect(),
        point_names: r.point_names.clone(),
        point_values: intervals(&r.point_values),
        processed: r.processed,
    }
}

/// The reply to a 6R inverse-kinematics request: the boxes of `linkspace ik6`.
pub(crate) fn ik6_response(chain: &Chain6R, found: &ArmIk6) -> InverseKinematics6Response {
    let one = ik6_solutions(found);
    InverseKinematics6Response {
        ok: true,
        message: one.message,
        complete: one.complete,
        solutions: one.solutions,
        joint_names: chain.joints.to_vec(),
        unique: one.unique,
        processed: one.processed,
        results: Vec::new(),
    }
}

/// The reply to a 6R inverse-kinematics request with many poses: each pose's answer (or why it
/// failed) in order.
pub(crate) fn ik6_many_response(answers: &[Result<crate::app::Answer, String>]) -> InverseKinematics6Response {
    let mut reply = InverseKinematics6Response { ok: true, ..Default::default() };
    let (mut complete, mut failed) = (0, 0);
    for answer in answers {
        let one = match answer {
            Ok(crate::app::Answer::Ik6(a)) => {
                if reply.joint_names.is_empty() {
                    reply.joint_names = a.chain.joints.to_vec();
                }
                ik6_solutions(&a.found)
            }
            Ok(other) => Ik6Solutions { ok: false, message: format!("internal error: a {} answer for a pose", other.name()), ..Default::default() },
            Err(message) => Ik6Solutions { ok: false, message: message.clone(), ..Default::default() },
        };
        complete += usize::from(one.complete);
        failed += usize::from(!one.ok);
        reply.results.push(one);
    }
    reply.complete = complete == answers.len();
    reply.message = format!("{} poses: {complete} complete, {} incomplete, {failed} failed", answers.len(), answers.len() - complete - failed);
    reply
}

/// One pose's boxes and counts.
fn ik6_solutions(found: &ArmIk6) -> Ik6Solutions {
    let s = &found.solutions;
    let mut message = format!("{} solutions proven unique, {} clusters undecided at sigma", s.unique.len(), s.clusters.len());
    if !s.curves.is_empty() {
        let kinds: Vec<&str> = s.curves.iter().map(|c| c.kind.name()).collect();
        message.push_str(&format!("; {} singular curves ({}), each a cluster of boxes after the others", s.curves.len(), kinds.join(", ")));
    }
    if let crate::app::Status::Stopped(limit) = s.status {
        message.push_str(&format!("; incomplete ({} limit): the clusters include the boxes left pending", limit.name()));
    }
    let as_box = |k: usize, b: &[crate::app::Interval; 6]| LsBox { intervals: b.iter().map(|x| msgs::Interval { lower: x.inf(), upper: x.sup() }).collect(), status: msgs::BOX_SOLUTION, level: 0, cluster: k as i32 };
    // Each unique box and each cluster its own cluster index; then one index per curve.
    let mut boxes: Vec<(usize, &[crate::app::Interval; 6])> = s.unique.iter().chain(s.clusters.iter().map(|c| &c.hull)).enumerate().collect();
    let first = boxes.len();
    boxes.extend(s.curves.iter().enumerate().flat_map(|(k, c)| c.cover.iter().map(move |b| (first + k, b))));
    Ik6Solutions {
        ok: true,
        message,
        complete: Completeness::of(s.status, s.clusters.len(), false).is_complete(),
        solutions: boxes.iter().map(|&(k, b)| as_box(k, b)).collect(),
        unique: (0..boxes.len()).map(|k| k < s.unique.len()).collect(),
        processed: s.stats.processed,
    }
}

/// The reply to a path check: the verdicts and reasons of `linkspace path-check`.
pub(crate) fn path_check_response(found: &ArmPathCheck) -> PathCheckResponse {
    let mut reply = PathCheckResponse {
        ok: true,
        message: found.headline(),
        complete: found.check.counts().not_decided == 0,
        singular_set: found.set.name().to_string(),
        subject: found.subject.clone(),
        joint_names: found.joints.clone(),
        ..Default::default()
    };
    for (k, v) in found.check.segments.iter().enumerate() {
        reply.verdicts.push(v.name().to_string());
        reply.reasons.push(v.reason(found.set.det()));
        let (sign, min_abs_det) = match v {
            SegmentVerdict::Clear { sign, min_abs_det, .. } => (if *sign > 0.0 { 1 } else { -1 }, *min_abs_det),
            _ => (0, 0.0),
        };
        reply.det_signs.push(sign);
        reply.min_abs_det.push(min_abs_det);
        if let SegmentVerdict::Crosses { crossings, .. } = v {
            for c in crossings {
                reply.crossing_segments.push(k.min(u32::MAX as usize) as u32);
                reply.crossing_t.push(msgs::Interval { lower: c.t[0], upper: c.t[1] });
                reply.crossing_joints.extend(c.joints.iter().map(|j| msgs::Interval { lower: j[0], upper: j[1] }));
            }
        }
    }
    reply
}

/// The reply to a collisions request: the boxes of `linkspace collisions`, over the sub-chain's
/// second and third joints.
pub(crate) fn collisions_response(found: &ArmCollisions) -> CollisionsResponse {
    let (scene, set) = (&found.scene, &found.set);
    let message = found.headline();
    let as_box = |theta: &[crate::app::Interval; 2], status: u8| LsBox { intervals: theta.iter().map(|x| msgs::Interval { lower: x.inf(), upper: x.sup() }).collect(), status, level: 0, cluster: -1 };
    let index = |k: usize| k.min(u32::MAX as usize) as u32;
    CollisionsResponse {
        ok: true,
        message,
        complete: set.completeness().is_complete(),
        joint_names: vec![scene.joints[1].clone(), scene.joints[2].clone()],
        body_names: scene.capsules().iter().map(|c| c.name.clone()).collect(),
        pair_first: scene.pairs().iter().map(|&(i, _)| index(i)).collect(),
        pair_second: scene.pairs().iter().map(|&(_, j)| index(j)).collect(),
        colliding: set.colliding.iter().map(|c| as_box(&c.theta, msgs::BOX_SOLUTION)).collect(),
        colliding_pairs: set.colliding.iter().map(|c| index(c.pair)).collect(),
        free: set.free.iter().map(|b| as_box(b, msgs::BOX_SOLUTION)).collect(),
        undecided: set.undecided.iter().map(|b| as_box(b, msgs::BOX_UNDECIDED)).collect(),
        processed: set.stats.processed,
    }
}

/// The reply to a self-motion request: the boxes of `linkspace self-motion`, over the seven
/// joints, each with its tag and cluster.
pub(crate) fn self_motion_response(found: &crate::app::ArmSelfMotion) -> SelfMotionResponse {
    let set = &found.set;
    let certified = set.certified();
    SelfMotionResponse {
        ok: true,
        message: found.headline(),
        complete: set.completeness().is_complete(),
        joint_names: set.joints.clone(),
        parameter: set.joints[set.parameter].clone(),
        boxes: set
            .boxes
            .iter()
            .map(|b| LsBox { intervals: b.joints.iter().map(|x| msgs::Interval { lower: x.inf(), upper: x.sup() }).collect(), status: box_status(b.tag), level: 0, cluster: b.cluster.min(i32::MAX as usize) as i32 })
            .collect(),
        clusters: set.clusters.min(u32::MAX as usize) as u32,
        certified: certified.min(u32::MAX as usize) as u32,
    }
}

/// At most `max` characters of `s` (a string from a request echoed into a reply or a log), with
/// how many were left out: replies stay small whatever a request carries.
pub fn bounded(s: &str, max: usize) -> String {
    let n = s.chars().count();
    if n <= max {
        return s.to_string();
    }
    let head: String = s.chars().take(max).collect();
    format!("{head}... ({} more characters)", n - max)
}

/// Longest name (mechanism, joint) echoed from a request into a reply.
pub(crate) const ECHO_NAME: usize = 120;
/// Longest message built from request data (an analysis error quoting it).
pub(crate) const ECHO_MESSAGE: usize = 2000;

/// The frame of joint-space markers and box sets of `mechanism`.
pub(crate) fn joint_frame(mechanism: &str) -> String {
    format!("{mechanism}/joint_space")
}

/// `/tf_static`: the joint-space frame of each mechanism (child) as an identity transform from
/// its root link (parent), so that RViz draws the joint-space markers without a hand-made one.
pub(crate) fn static_transforms(frames: &[(String, String)]) -> TfMessage {
    TfMessage {
        transforms: frames
            .iter()
            .map(|(parent, child)| TransformStamped {
                header: header(parent),
                child_frame_id: child.clone(),
                transform: Transform { translation: Vector3::default(), rotation: Quaternion { w: 1.0, ..Default::default() } },
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report_of(xml: &str, nodes: bool) -> SingularityReport {
        let m = crate::app::parse_urdf(xml).expect("parses");
        let a = crate::app::load(&m, &[], &[]).expect("loads");
        let q = crate::app::SingularityQuery { precision: 1e-4, nodes, max_boxes: 1_000_000, timeout: None, threads: 1 };
        let r = a.singularities(&q).expect("valid").run(&std::sync::atomic::AtomicBool::new(false), &mut |_| {}).expect("runs");
        singularity_report(&r, 7)
    }

    #[test]
    fn verdict_and_branches_reach_the_report() {
        // PUMA 560 (axes 2 and 3 parallel): non-cuspidal, 4 aspects, at most 4 solutions, three
        // branches crossing in 4 points, each crossing on a theta3 line and the fold of g.
        let p = report_of(include_str!("../../../urdf/puma560.urdf"), true);
        assert_eq!((p.cuspidal, p.aspects, p.max_ik_solutions, p.verdict_certified), (msgs::NO, 4, 4, true), "{}", p.verdict_reason);
        assert!(p.verdict_reason.contains("exactly parallel"));
        assert_eq!(p.branch_names, ["outstretched", "folded", "fold_of_g"]);
        assert_eq!(p.branch_kinds, ["theta3_line", "theta3_line", "curve"]);
        assert_eq!(p.branch_curve_of_nodes, [msgs::YES; 3]);
        assert_eq!((p.branch_descriptions.len(), p.branch_proofs.len(), p.branch_image_descriptions.len(), p.branch_images.len()), (3, 3, 3, 6));
        let c = &p.branch_crossings;
        assert_eq!((c.analysis.as_str(), c.dim, c.status, c.lower.len(), c.joint_lower.len()), ("branch_crossings", 4, msgs::SET_COMPLETE, 16, 8));
        assert_eq!(c.variable_names, ["joint_2", "joint_3", "radius", "z"]);
        assert_eq!(c.box_status, [msgs::BOX_UNIQUE; 4]);
        assert_eq!(p.crossing_names.len(), 4);
        assert_eq!(p.crossing_branches, [0, 2, 0, 2, 1, 2, 1, 2]);
        // Box i's joint part is its first two variables; its image lies in the fold of g's.
        for i in 0..4 {
            assert_eq!(c.joint_lower[2 * i..2 * i + 2], c.lower[4 * i..4 * i + 2]);
            let radius = &p.branch_images[2 * 2];
            assert!(radius.lower <= c.lower[4 * i + 2] && c.upper[4 * i + 2] <= radius.upper);
        }
        // Nodes are not searched there (curves of nodes), cusps excluded by the proof.
        assert!(p.complete && p.cusps.is_empty() && p.nodes.is_empty(), "{}", p.message);
        assert!(p.branches_no_cusp_proven && !p.branches_argument.is_empty());

        // Robot e: cuspidal, 2 aspects, 4 solutions; no branches.
        let e = report_of(include_str!("../../../urdf/orthogonal_3r_e.urdf"), false);
        assert_eq!((e.cuspidal, e.aspects, e.max_ik_solutions, e.verdict_certified), (msgs::YES, 2, 4, true), "{}", e.verdict_reason);
        assert!(e.branch_names.is_empty() && e.crossing_names.is_empty() && e.branch_crossings.lower.is_empty());
        assert_eq!((e.branch_crossings.status, e.branch_crossings.dim), (msgs::SET_COMPLETE, 4));

        // A linkage: unknown, with the reason; and a refusal's empty report likewise.
        let four_bar = report_of(include_str!("../../../urdf/four_bar.urdf"), false);
        for r in [&four_bar, &no_report()] {
            assert_eq!((r.cuspidal, r.aspects, r.max_ik_solutions, r.verdict_certified), (msgs::UNKNOWN, -1, -1, false));
            assert!(r.branch_names.is_empty());
        }
        assert!(four_bar.verdict_reason.contains("3R manipulators only"));
        assert_eq!((tri_state(Some(true)), tri_state(Some(false)), tri_state(None)), (1, 0, -1));
    }

    #[test]
    fn echoed_strings_are_bounded() {
        let long = "x".repeat(65_300);
        let b = bounded(&long, ECHO_NAME);
        assert!(b.len() < 200 && b.ends_with("(65180 more characters)"), "{b}");
        assert_eq!(bounded("four_bar", ECHO_NAME), "four_bar");
        assert_eq!(bounded("ééé", 2), "éé... (1 more characters)");
    }
}

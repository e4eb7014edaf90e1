//! From the analysis layer's plain results to wire types: box sets, markers, joint states.

use super::msgs::{
    self, BoxSet, ColorRGBA, CuspRecord, Header, InverseKinematicsResponse, JointState, LsBox, Marker, MarkerArray, NodeRecord, Point, Pose, Quaternion, SingularityReport, SolveStats,
    Time, Vector3,
};
use crate::analysis::{Bounds, BoxSetResult, IkResult, SingularityResult};
use crate::search::{BoxStatus, Limit, SolverSettings, Status};

/// A header stamped now (wall clock) in `frame`.
pub fn header(frame: &str) -> Header {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
    Header { stamp: Time { sec: now.as_secs().min(i32::MAX as u64) as i32, nanosec: now.subsec_nanos() }, frame_id: frame.to_string() }
}

/// The wire form of the settings (`timeout` 0 for none).
pub fn settings(s: &SolverSettings) -> msgs::Settings {
    msgs::Settings { sigma: s.sigma, rho: s.rho, max_boxes: s.max_boxes, timeout: s.timeout.map_or(0.0, |t| t.as_secs_f64()) }
}

/// The name of a limit, as in the JSON report.
pub fn limit_name(l: Limit) -> &'static str {
    l.name()
}

/// A result as a `linkspace_msgs/BoxSet`, boxes in the result's order.
pub fn box_set(r: &BoxSetResult, run_id: u64) -> BoxSet {
    let n = r.boxes.len();
    let (mut lower, mut upper) = (Vec::with_capacity(n * r.variables.len()), Vec::with_capacity(n * r.variables.len()));
    let (mut joint_lower, mut joint_upper) = (Vec::with_capacity(n * r.joint_names.len()), Vec::with_capacity(n * r.joint_names.len()));
    for b in &r.boxes {
        lower.extend(b.bounds.iter().map(|x| x[0]));
        upper.extend(b.bounds.iter().map(|x| x[1]));
        joint_lower.extend(b.joints.iter().map(|x| x[0]));
        joint_upper.extend(b.joints.iter().map(|x| x[1]));
    }
    let (status, limit) = match r.status {
        Status::Complete => (msgs::SET_COMPLETE, ""),
        Status::Incomplete(l) => (msgs::SET_INCOMPLETE, limit_name(l)),
    };
    BoxSet {
        header: header(""),
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
        box_status: r.boxes.iter().map(|b| if b.status == BoxStatus::Solution { msgs::BOX_SOLUTION } else { msgs::BOX_UNDECIDED }).collect(),
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
        },
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
pub fn markers(r: &BoxSetResult, world_frame: &str, cap: usize) -> MarkerArray {
    let mut markers = vec![Marker { header: header(world_frame), action: msgs::marker::DELETEALL, ..Default::default() }];
    let joint_frame = format!("{}/joint_space", r.mechanism);
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
            let [x, y] = b.traces[t];
            let c = [0.5 * (x[0] + x[1]), 0.5 * (y[0] + y[1]), 0.0];
            markers.push(cube(world_frame, &ns, id, c, [x[1] - x[0], y[1] - y[0], 0.0], colour(b.cluster)));
            id += 1;
        }
    }
    MarkerArray { markers }
}

/// One `sensor_msgs/JointState` per isolated solution (assembly mode), in cluster order; the
/// header's frame_id says which mode it is, e.g. `mode 1 of 2 (cluster 1)`.
pub fn assembly_modes(r: &BoxSetResult) -> Vec<JointState> {
    let modes = r.assembly_modes();
    let n = modes.len();
    modes
        .into_iter()
        .enumerate()
        .map(|(k, m)| JointState {
            header: header(&format!("mode {} of {n} (cluster {})", k + 1, m.cluster)),
            name: m.joints.iter().map(|(j, _)| j.clone()).collect(),
            position: m.joints.iter().map(|(_, v)| *v).collect(),
            velocity: vec![],
            effort: vec![],
        })
        .collect()
}

fn intervals(b: &[Bounds]) -> Vec<msgs::Interval> {
    b.iter().map(|x| msgs::Interval { lower: x[0], upper: x[1] }).collect()
}

/// A singularity result as a `linkspace_msgs/SingularityReport`, records in the result's order.
pub fn singularity_report(r: &SingularityResult, run_id: u64) -> SingularityReport {
    SingularityReport {
        header: header(""),
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
        complete: r.status == Status::Complete,
        precision: r.query.precision,
    }
}

fn sphere(frame: &str, ns: &str, id: i32, centre: [f64; 3], size: f64, color: ColorRGBA) -> Marker {
    Marker { r#type: msgs::marker::SPHERE, ..cube(frame, ns, id, centre, [size; 3], color) }
}

/// Markers for RViz of a singularity result, all in frame `<robot>/joint_space` over the
/// record joints (x, y; radians as metres): a `DELETEALL`, then namespace `singular_curves`
/// (one flat cube per cover box, coloured by piece), `internal_motions` (one flat cube per
/// line), `cusps` (red spheres; grey when undecided) and `nodes` (blue spheres, one per point
/// of each pair). At most `cap` markers per namespace.
pub fn singularity_markers(r: &SingularityResult, cap: usize) -> MarkerArray {
    let frame = format!("{}/joint_space", r.mechanism);
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
pub fn ik_response(r: &IkResult) -> InverseKinematicsResponse {
    let unique = r.solutions.iter().filter(|s| s.unique).count();
    let clusters = r.solutions.len() - unique;
    let mut message = format!("{unique} solutions proven unique, {clusters} clusters undecided at sigma (each may hold one or several solutions, or a line of them)");
    if let crate::search::Status::Incomplete(limit) = r.status {
        message.push_str(&format!("; incomplete ({} limit): the clusters include the boxes left pending", limit.name()));
    }
    InverseKinematicsResponse {
        ok: true,
        message,
        complete: r.status.is_complete(),
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

/// Largest service reply the node sends, in bytes of CDR (estimated). Replies sent as several
/// DDS fragments never reached rclpy (Fast DDS 2.14) in our tests: a 35 KB Solve reply
/// arrived, a 90 KB one did not, while box sets of a megabyte arrive on topics. So replies stay
/// under one datagram, and what does not fit is on the mechanism's topics.
pub const REPLY_BUDGET: usize = 48 * 1024;

/// Estimated CDR size of a box set.
pub fn box_set_bytes(s: &BoxSet) -> usize {
    let names: usize = s.variable_names.iter().chain(&s.joint_names).chain(&s.fixed_joint_names).map(|n| n.len() + 8).sum();
    8 * (s.lower.len() + s.upper.len() + s.joint_lower.len() + s.joint_upper.len() + s.fixed_joint_values.len()) + 9 * s.box_status.len() + names + 256
}

/// Clears the boxes of a set, keeping its header, status, settings, names and counters.
pub fn strip_boxes(s: &mut BoxSet) {
    for v in [&mut s.lower, &mut s.upper, &mut s.joint_lower, &mut s.joint_upper] {
        v.clear();
    }
    s.box_status.clear();
    s.level.clear();
    s.cluster.clear();
}

fn record_bytes(joints: usize, workspace: usize) -> usize {
    16 * (joints + workspace) + 16
}

/// Estimated CDR size of a singularity report.
pub fn singularity_bytes(r: &SingularityReport) -> usize {
    box_set_bytes(&r.singular_curves)
        + box_set_bytes(&r.internal_motions)
        + r.cusps.iter().map(|c| record_bytes(c.joints.len(), c.workspace.len())).sum::<usize>()
        + r.nodes.iter().map(|n| record_bytes(n.joints_a.len() + n.joints_b.len(), n.workspace.len())).sum::<usize>()
        + r.message.len()
        + 512
}

/// Makes a singularity report fit in a service reply: the singular-curve cover goes (it is the
/// same for every run and is on the `singularities` topic), then undecided records from the
/// end, and the report is then marked incomplete. Returns what was left out, for the message.
pub fn fit_singularity_reply(r: &mut SingularityReport, topic: &str) -> Option<String> {
    if singularity_bytes(r) <= REPLY_BUDGET {
        return None;
    }
    let mut notes = Vec::new();
    if !r.singular_curves.box_status.is_empty() {
        notes.push(format!("the {} boxes of the singular-curve cover are left out of this reply (they are on {topic})", r.singular_curves.box_status.len()));
        strip_boxes(&mut r.singular_curves);
    }
    let mut dropped = 0;
    while singularity_bytes(r) > REPLY_BUDGET {
        if r.nodes.last().is_some_and(|n| !n.certified) {
            r.nodes.pop();
        } else if r.cusps.last().is_some_and(|c| !c.certified) {
            r.cusps.pop();
        } else {
            break;
        }
        dropped += 1;
    }
    if dropped > 0 {
        r.complete = false;
        notes.push(format!("{dropped} undecided records are left out (a service reply must stay under {} KiB), so this reply does not enclose every singularity", REPLY_BUDGET / 1024));
    }
    Some(notes.join("; "))
}

/// Makes an inverse-kinematics reply fit: clusters go from the end, and the reply is then
/// marked incomplete. Returns what was left out, for the message.
pub fn fit_ik_reply(r: &mut InverseKinematicsResponse) -> Option<String> {
    let bytes = |r: &InverseKinematicsResponse| r.solutions.iter().map(|b| 16 * b.intervals.len() + 24).sum::<usize>() + r.message.len() + 512;
    let mut dropped = 0;
    while bytes(r) > REPLY_BUDGET && r.unique.last() == Some(&false) {
        r.solutions.pop();
        r.unique.pop();
        r.merged_boxes.pop();
        dropped += 1;
    }
    (dropped > 0).then(|| {
        r.complete = false;
        format!("{dropped} clusters are left out (a service reply must stay under {} KiB), so this reply does not enclose every solution: ask again with a smaller max_boxes or a larger sigma", REPLY_BUDGET / 1024)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(boxes: usize, dim: usize) -> BoxSet {
        BoxSet { lower: vec![0.0; boxes * dim], upper: vec![1.0; boxes * dim], box_status: vec![0; boxes], level: vec![0; boxes], cluster: vec![0; boxes], dim: dim as u32, ..Default::default() }
    }

    #[test]
    fn replies_are_cut_to_the_budget_with_a_reason() {
        let small = set(100, 2);
        assert!(box_set_bytes(&small) < REPLY_BUDGET);
        let mut r = SingularityReport { singular_curves: set(3000, 2), complete: true, ..Default::default() };
        let certified = CuspRecord { joints: vec![Default::default(); 2], workspace: vec![Default::default(); 2], certified: true };
        r.cusps = vec![certified.clone(); 4];
        r.cusps.extend(vec![CuspRecord { certified: false, ..certified.clone() }; 2000]);
        let note = fit_singularity_reply(&mut r, "/t").expect("too big");
        assert!(note.contains("3000 boxes of the singular-curve cover") && note.contains("undecided records are left out"), "{note}");
        assert!(singularity_bytes(&r) <= REPLY_BUDGET && !r.complete);
        assert_eq!(r.cusps.iter().filter(|c| c.certified).count(), 4, "certified records stay");
        let mut fits = SingularityReport { singular_curves: small, complete: true, ..Default::default() };
        assert_eq!(fit_singularity_reply(&mut fits, "/t"), None);
        assert!(fits.complete && fits.singular_curves.box_status.len() == 100);

        let one = LsBox { intervals: vec![Default::default(); 3], ..Default::default() };
        let mut ik = InverseKinematicsResponse { complete: true, solutions: vec![one; 3000], unique: vec![false; 3000], merged_boxes: vec![1; 3000], ..Default::default() };
        ik.unique[0] = true;
        assert!(fit_ik_reply(&mut ik).expect("too big").contains("clusters are left out"));
        assert!(!ik.complete && ik.unique[0] && ik.solutions.len() == ik.unique.len() && ik.solutions.len() < 3000);
    }
}

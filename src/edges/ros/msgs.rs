//! Wire types: `linkspace_msgs` (msgs/, the source of truth) mirrored field for field, plus the
//! few standard ROS 2 types the node publishes (std_msgs, geometry_msgs, sensor_msgs,
//! visualization_msgs as of Jazzy).
//!
//! CDR is positional: a field out of order or of another width garbles everything after it.
//! So every struct is declared through `mirror!`, which also records its field names and Rust
//! types; the test at the bottom parses `msgs/msg/*.msg` and `msgs/srv/*.srv` and checks them.
//! A request or message without fields carries ROS's placeholder byte
//! `structure_needs_at_least_one_member`, as rosidl generates it.

use ros2_client::Message;
use serde::{Deserialize, Serialize};

/// The fields of a mirrored struct: (name, Rust type as written), which the layout test at the
/// bottom reads.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) trait Mirror {
    /// In declaration (= wire) order.
    const FIELDS: &'static [(&'static str, &'static str)];
}

macro_rules! mirror {
    ($(#[$meta:meta])* $name:ident { $($(#[$fmeta:meta])* $field:ident : $ty:ty),* $(,)? }) => {
        $(#[$meta])*
        #[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
        pub(crate) struct $name {
            // Fields are documented in msgs/, the source of truth.
            $($(#[$fmeta])* #[allow(missing_docs)] pub(crate) $field: $ty,)*
        }
        impl Message for $name {}
        impl Mirror for $name {
            const FIELDS: &'static [(&'static str, &'static str)] = &[$((stringify!($field), stringify!($ty))),*];
        }
    };
}

// ---- builtin_interfaces, std_msgs, geometry_msgs ----

mirror! {
    /// builtin_interfaces/Time
    Time { sec: i32, nanosec: u32 }
}
mirror! {
    /// builtin_interfaces/Duration
    Duration { sec: i32, nanosec: u32 }
}
mirror! {
    /// std_msgs/Header
    Header { stamp: Time, frame_id: String }
}
mirror! {
    /// std_msgs/ColorRGBA
    ColorRGBA { r: f32, g: f32, b: f32, a: f32 }
}
mirror! {
    /// geometry_msgs/Point
    Point { x: f64, y: f64, z: f64 }
}
mirror! {
    /// geometry_msgs/Vector3
    Vector3 { x: f64, y: f64, z: f64 }
}
mirror! {
    /// geometry_msgs/Quaternion
    Quaternion { x: f64, y: f64, z: f64, w: f64 }
}
mirror! {
    /// geometry_msgs/Pose
    Pose { position: Point, orientation: Quaternion }
}

// ---- trajectory_msgs ----

mirror! {
    /// trajectory_msgs/JointTrajectoryPoint
    JointTrajectoryPoint { positions: Vec<f64>, velocities: Vec<f64>, accelerations: Vec<f64>, effort: Vec<f64>, time_from_start: Duration }
}
mirror! {
    /// trajectory_msgs/JointTrajectory
    JointTrajectory { header: Header, joint_names: Vec<String>, points: Vec<JointTrajectoryPoint> }
}

// ---- sensor_msgs, visualization_msgs ----

mirror! {
    /// sensor_msgs/JointState
    JointState { header: Header, name: Vec<String>, position: Vec<f64>, velocity: Vec<f64>, effort: Vec<f64> }
}
mirror! {
    /// sensor_msgs/CompressedImage
    CompressedImage { header: Header, format: String, data: Vec<u8> }
}
mirror! {
    /// visualization_msgs/UVCoordinate
    UVCoordinate { u: f32, v: f32 }
}
mirror! {
    /// visualization_msgs/MeshFile
    MeshFile { filename: String, data: Vec<u8> }
}
mirror! {
    /// visualization_msgs/Marker (Jazzy)
    Marker {
        header: Header,
        ns: String,
        id: i32,
        r#type: i32,
        action: i32,
        pose: Pose,
        scale: Vector3,
        color: ColorRGBA,
        lifetime: Duration,
        frame_locked: bool,
        points: Vec<Point>,
        colors: Vec<ColorRGBA>,
        texture_resource: String,
        texture: CompressedImage,
        uv_coordinates: Vec<UVCoordinate>,
        text: String,
        mesh_resource: String,
        mesh_file: MeshFile,
        mesh_use_embedded_materials: bool,
    }
}
mirror! {
    /// visualization_msgs/MarkerArray
    MarkerArray { markers: Vec<Marker> }
}

/// `visualization_msgs/Marker` type and action constants used here.
pub(crate) mod marker {
    /// CUBE
    pub(crate) const CUBE: i32 = 1;
    /// SPHERE
    pub(crate) const SPHERE: i32 = 2;
    /// ADD
    pub(crate) const ADD: i32 = 0;
    /// DELETEALL
    pub(crate) const DELETEALL: i32 = 3;
}

// ---- linkspace_msgs/msg ----

mirror! {
    /// linkspace_msgs/Interval
    Interval { lower: f64, upper: f64 }
}
mirror! {
    /// linkspace_msgs/Box (`LsBox` in Rust, where `Box` is taken)
    LsBox { intervals: Vec<Interval>, status: u8, level: u32, cluster: i32 }
}
/// `Box.SOLUTION`
pub(crate) const BOX_SOLUTION: u8 = 0;
/// `Box.UNDECIDED`
pub(crate) const BOX_UNDECIDED: u8 = 1;
/// `Box.UNIQUE`
pub(crate) const BOX_UNIQUE: u8 = 2;

mirror! {
    /// linkspace_msgs/Settings
    Settings { sigma: f64, rho: f64, max_boxes: u64, timeout: f64 }
}
mirror! {
    /// linkspace_msgs/SolveStats
    SolveStats { processed: u64, empty: u64, bisected: u64, solutions: u64, spurious_dropped: u64, max_level: u32, seconds: f64, certified: u64, post_processing_cut_short: bool }
}
mirror! {
    /// linkspace_msgs/BoxSet
    BoxSet {
        header: Header,
        mechanism: String,
        analysis: String,
        run_id: u64,
        status: u8,
        limit: String,
        settings: Settings,
        variable_names: Vec<String>,
        dim: u32,
        lower: Vec<f64>,
        upper: Vec<f64>,
        box_status: Vec<u8>,
        level: Vec<u32>,
        cluster: Vec<i32>,
        clusters: u32,
        joint_names: Vec<String>,
        joint_lower: Vec<f64>,
        joint_upper: Vec<f64>,
        fixed_joint_names: Vec<String>,
        fixed_joint_values: Vec<f64>,
        stats: SolveStats,
        merged_from: u64,
    }
}
/// `BoxSet.COMPLETE`
pub(crate) const SET_COMPLETE: u8 = 0;
/// `BoxSet.INCOMPLETE`
pub(crate) const SET_INCOMPLETE: u8 = 1;

mirror! {
    /// linkspace_msgs/CuspRecord
    CuspRecord { joints: Vec<Interval>, workspace: Vec<Interval>, certified: bool }
}
mirror! {
    /// linkspace_msgs/NodeRecord
    NodeRecord { joints_a: Vec<Interval>, joints_b: Vec<Interval>, workspace: Vec<Interval>, certified: bool }
}
mirror! {
    /// linkspace_msgs/SingularityReport
    SingularityReport {
        header: Header,
        mechanism: String,
        run_id: u64,
        ok: bool,
        message: String,
        singular_curves: BoxSet,
        cusps: Vec<CuspRecord>,
        nodes: Vec<NodeRecord>,
        internal_motions: BoxSet,
        joint_names: Vec<String>,
        workspace_names: Vec<String>,
        complete: bool,
        precision: f64,
        limit: String,
        set_kinds: Vec<String>,
        sets: Vec<BoxSet>,
        set_proven: Vec<u32>,
        set_undecided: Vec<u32>,
        set_verdicts: Vec<String>,
        actuated: Vec<String>,
        actuated_source: String,
        cuspidal: i8,
        aspects: i32,
        max_ik_solutions: i32,
        verdict_certified: bool,
        verdict_reason: String,
        branch_names: Vec<String>,
        branch_kinds: Vec<String>,
        branch_descriptions: Vec<String>,
        branch_image_descriptions: Vec<String>,
        branch_curve_of_nodes: Vec<i8>,
        branch_proofs: Vec<String>,
        branch_images: Vec<Interval>,
        branch_crossings: BoxSet,
        crossing_names: Vec<String>,
        crossing_branches: Vec<u32>,
        branch_isolated_nodes: Vec<NodeRecord>,
        branches_no_cusp_proven: bool,
        branches_argument: String,
        arm_cuspidality: String,
        arm_cuspidality_reason: String,
    }
}
/// `SingularityReport.YES` (a tri-state field: cuspidal, branch_curve_of_nodes)
pub(crate) const YES: i8 = 1;
/// `SingularityReport.NO`
pub(crate) const NO: i8 = 0;
/// `SingularityReport.UNKNOWN`
pub(crate) const UNKNOWN: i8 = -1;
mirror! {
    /// linkspace_msgs/Progress
    Progress { header: Header, mechanism: String, analysis: String, run_id: u64, processed: u64, pending: u64, decided: f64, done: bool }
}
mirror! {
    /// linkspace_msgs/MechanismInfo
    MechanismInfo {
        name: String,
        kind: String,
        services: Vec<String>,
        free_joints: Vec<String>,
        fixed_joint_names: Vec<String>,
        fixed_joint_values: Vec<f64>,
        state: String,
        message: String,
        topic_prefix: String,
    }
}

// ---- linkspace_msgs/srv ----

mirror! {
    /// linkspace_msgs/Solve request
    SolveRequest { mechanism: String, fixed_joint_names: Vec<String>, fixed_joint_values: Vec<f64>, settings: Settings, wait: f64 }
}
mirror! {
    /// linkspace_msgs/Solve response
    SolveResponse { ok: bool, message: String, run_id: u64, done: bool, result: BoxSet }
}
mirror! {
    /// linkspace_msgs/Cancel request
    CancelRequest { run_id: u64 }
}
mirror! {
    /// linkspace_msgs/Cancel response
    CancelResponse { ok: bool, message: String }
}
mirror! {
    /// linkspace_msgs/Singularities request
    SingularitiesRequest { mechanism: String, precision: f64, nodes: bool, max_boxes: u64, timeout: f64 }
}
mirror! {
    /// linkspace_msgs/Singularities response
    SingularitiesResponse { ok: bool, message: String, report: SingularityReport }
}
mirror! {
    /// linkspace_msgs/InverseKinematics request
    InverseKinematicsRequest { mechanism: String, point: Point, sigma: f64, max_boxes: u64 }
}
mirror! {
    /// linkspace_msgs/InverseKinematics response
    InverseKinematicsResponse {
        ok: bool,
        message: String,
        complete: bool,
        solutions: Vec<LsBox>,
        joint_names: Vec<String>,
        unique: Vec<bool>,
        merged_boxes: Vec<u32>,
        point_names: Vec<String>,
        point_values: Vec<Interval>,
        processed: u64,
    }
}
mirror! {
    /// linkspace_msgs/InverseKinematics6 request
    InverseKinematics6Request { mechanism: String, pose: Pose, sigma: f64, max_boxes: u64, poses: Vec<Pose> }
}
mirror! {
    /// linkspace_msgs/InverseKinematics6 response
    InverseKinematics6Response {
        ok: bool,
        message: String,
        complete: bool,
        solutions: Vec<LsBox>,
        joint_names: Vec<String>,
        unique: Vec<bool>,
        processed: u64,
        results: Vec<Ik6Solutions>,
    }
}
mirror! {
    /// linkspace_msgs/Ik6Solutions
    Ik6Solutions { ok: bool, message: String, complete: bool, solutions: Vec<LsBox>, unique: Vec<bool>, processed: u64 }
}
mirror! {
    /// linkspace_msgs/PathCheck request
    PathCheckRequest { mechanism: String, trajectory: JointTrajectory, tolerance: f64, timeout: f64, singular_set: String }
}
mirror! {
    /// linkspace_msgs/PathCheck response
    PathCheckResponse {
        ok: bool,
        message: String,
        complete: bool,
        singular_set: String,
        subject: String,
        joint_names: Vec<String>,
        verdicts: Vec<String>,
        reasons: Vec<String>,
        det_signs: Vec<i8>,
        min_abs_det: Vec<f64>,
        crossing_segments: Vec<u32>,
        crossing_t: Vec<Interval>,
        crossing_joints: Vec<Interval>,
    }
}
mirror! {
    /// linkspace_msgs/Collisions request
    CollisionsRequest { mechanism: String, precision: f64, max_boxes: u64 }
}
mirror! {
    /// linkspace_msgs/Collisions response
    CollisionsResponse {
        ok: bool,
        message: String,
        complete: bool,
        joint_names: Vec<String>,
        body_names: Vec<String>,
        pair_first: Vec<u32>,
        pair_second: Vec<u32>,
        colliding: Vec<LsBox>,
        colliding_pairs: Vec<u32>,
        free: Vec<LsBox>,
        undecided: Vec<LsBox>,
        processed: u64,
    }
}
mirror! {
    /// linkspace_msgs/SelfMotion request
    SelfMotionRequest { mechanism: String, pose: Pose, parameter: String, range_lower: f64, range_upper: f64, cell: f64, precision: f64, max_boxes: u64 }
}
mirror! {
    /// linkspace_msgs/SelfMotion response
    SelfMotionResponse { ok: bool, message: String, complete: bool, joint_names: Vec<String>, parameter: String, boxes: Vec<LsBox>, clusters: u32, certified: u32 }
}
mirror! {
    /// linkspace_msgs/Classify request
    ClassifyRequest { mechanism: String, joint_names: Vec<String>, joint_values: Vec<f64> }
}
mirror! {
    /// linkspace_msgs/Classify response
    ClassifyResponse {
        ok: bool,
        message: String,
        inside: bool,
        component: i32,
        components: u32,
        distance: f64,
        singular_distance_known: bool,
        singular_distance: f64,
    }
}
mirror! {
    /// linkspace_msgs/ListMechanisms request (no fields: rosidl's placeholder byte)
    ListMechanismsRequest { structure_needs_at_least_one_member: u8 }
}
mirror! {
    /// linkspace_msgs/ListMechanisms response
    ListMechanismsResponse { mechanisms: Vec<MechanismInfo> }
}
mirror! {
    /// linkspace_msgs/AssemblyMode
    AssemblyMode {
        header: Header,
        mechanism: String,
        run_id: u64,
        mode: u32,
        modes: u32,
        cluster: i32,
        joint_names: Vec<String>,
        positions: Vec<f64>,
    }
}

// ---- linkspace_msgs/action/Solve (goal, result, feedback) ----

mirror! {
    /// linkspace_msgs/action/Solve goal
    SolveGoal { mechanism: String, fixed_joint_names: Vec<String>, fixed_joint_values: Vec<f64>, settings: Settings }
}
mirror! {
    /// linkspace_msgs/action/Solve result
    SolveActionResult { ok: bool, message: String, run_id: u64, result: BoxSet }
}
mirror! {
    /// linkspace_msgs/action/Solve feedback
    SolveFeedback { progress: Progress }
}

// ---- tf2_msgs, std_msgs/String ----

mirror! {
    /// geometry_msgs/Transform
    Transform { translation: Vector3, rotation: Quaternion }
}
mirror! {
    /// geometry_msgs/TransformStamped
    TransformStamped { header: Header, child_frame_id: String, transform: Transform }
}
mirror! {
    /// tf2_msgs/TFMessage
    TfMessage { transforms: Vec<TransformStamped> }
}
mirror! {
    /// std_msgs/String (the `/robot_description` topic)
    StringMsg { data: String }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Rust type a ROS field type must be mirrored by.
    fn rust_type(ros: &str) -> String {
        if let Some(inner) = ros.strip_suffix("[]") {
            return format!("Vec<{}>", rust_type(inner));
        }
        let base = ros.rsplit('/').next().expect("split yields one item");
        match base {
            "bool" => "bool",
            "uint8" | "byte" => "u8",
            "int8" => "i8",
            "int32" => "i32",
            "uint32" => "u32",
            "int64" => "i64",
            "uint64" => "u64",
            "float32" => "f32",
            "float64" => "f64",
            "string" => "String",
            "Box" => "LsBox",
            other => other,
        }
        .to_string()
    }

    /// (name, type) of every field of a .msg text (or one half of a .srv), constants and
    /// comments left out.
    fn fields(text: &str) -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = text
            .lines()
            .map(|l| l.split('#').next().expect("split yields one item").trim())
            .filter(|l| !l.is_empty() && !l.contains('='))
            .map(|l| {
                let mut parts = l.split_whitespace();
                let ty = parts.next().expect("type").to_string();
                let name = parts.next().unwrap_or_else(|| panic!("no field name in '{l}'")).to_string();
                (name, rust_type(&ty))
            })
            .collect();
        if out.is_empty() {
            out.push(("structure_needs_at_least_one_member".into(), "u8".into()));
        }
        out
    }

    fn mirrored<T: Mirror>() -> Vec<(String, String)> {
        T::FIELDS.iter().map(|(n, t)| (n.trim_start_matches("r#").to_string(), t.chars().filter(|c| !c.is_whitespace()).collect())).collect()
    }

    fn read(path: &str) -> String {
        std::fs::read_to_string(format!("{}/msgs/{path}", env!("CARGO_MANIFEST_DIR"))).unwrap_or_else(|e| panic!("msgs/{path}: {e}"))
    }

    #[test]
    fn rust_mirrors_match_the_interface_files() {
        let msgs: Vec<(&str, Vec<(String, String)>)> = vec![
            ("Interval", mirrored::<Interval>()),
            ("Box", mirrored::<LsBox>()),
            ("Settings", mirrored::<Settings>()),
            ("SolveStats", mirrored::<SolveStats>()),
            ("BoxSet", mirrored::<BoxSet>()),
            ("CuspRecord", mirrored::<CuspRecord>()),
            ("NodeRecord", mirrored::<NodeRecord>()),
            ("SingularityReport", mirrored::<SingularityReport>()),
            ("Progress", mirrored::<Progress>()),
            ("MechanismInfo", mirrored::<MechanismInfo>()),
            ("AssemblyMode", mirrored::<AssemblyMode>()),
            ("Ik6Solutions", mirrored::<Ik6Solutions>()),
        ];
        type Fields = Vec<(String, String)>;
        let srvs: Vec<(&str, Fields, Fields)> = vec![
            ("Solve", mirrored::<SolveRequest>(), mirrored::<SolveResponse>()),
            ("Cancel", mirrored::<CancelRequest>(), mirrored::<CancelResponse>()),
            ("Singularities", mirrored::<SingularitiesRequest>(), mirrored::<SingularitiesResponse>()),
            ("InverseKinematics", mirrored::<InverseKinematicsRequest>(), mirrored::<InverseKinematicsResponse>()),
            ("Classify", mirrored::<ClassifyRequest>(), mirrored::<ClassifyResponse>()),
            ("InverseKinematics6", mirrored::<InverseKinematics6Request>(), mirrored::<InverseKinematics6Response>()),
            ("PathCheck", mirrored::<PathCheckRequest>(), mirrored::<PathCheckResponse>()),
            ("Collisions", mirrored::<CollisionsRequest>(), mirrored::<CollisionsResponse>()),
            ("SelfMotion", mirrored::<SelfMotionRequest>(), mirrored::<SelfMotionResponse>()),
            ("ListMechanisms", mirrored::<ListMechanismsRequest>(), mirrored::<ListMechanismsResponse>()),
        ];
        for (name, mirror) in &msgs {
            assert_eq!(&fields(&read(&format!("msg/{name}.msg"))), mirror, "msg/{name}.msg");
        }
        let actions: Vec<(&str, [Fields; 3])> = vec![("Solve", [mirrored::<SolveGoal>(), mirrored::<SolveActionResult>(), mirrored::<SolveFeedback>()])];
        for (name, parts) in &actions {
            let text = read(&format!("action/{name}.action"));
            let got: Vec<&str> = text.split("\n---").collect();
            assert_eq!(got.len(), 3, "action/{name}.action has goal, result and feedback");
            for (k, (part, mirror)) in got.iter().zip(parts).enumerate() {
                assert_eq!(&fields(part), mirror, "action/{name}.action part {k}");
            }
        }
        for (name, request, response) in &srvs {
            let text = read(&format!("srv/{name}.srv"));
            let (req, resp) = text.split_once("\n---").unwrap_or_else(|| panic!("srv/{name}.srv has no ---"));
            assert_eq!(&fields(req), request, "srv/{name}.srv request");
            assert_eq!(&fields(resp), response, "srv/{name}.srv response");
        }
        // Every interface file is mirrored and listed in CMakeLists.txt.
        let cmake = read("CMakeLists.txt");
        for dir in ["msg", "srv", "action"] {
            let files = std::fs::read_dir(format!("{}/msgs/{dir}", env!("CARGO_MANIFEST_DIR"))).expect("msgs dir");
            for f in files {
                let f = f.expect("entry").file_name().into_string().expect("utf-8");
                let stem = f.split('.').next().expect("stem");
                let mirrored = match dir {
                    "msg" => msgs.iter().any(|(n, _)| *n == stem),
                    "srv" => srvs.iter().any(|(n, _, _)| *n == stem),
                    _ => actions.iter().any(|(n, _)| *n == stem),
                };
                assert!(mirrored, "{dir}/{f} has no Rust mirror");
                assert!(cmake.contains(&format!("\"{dir}/{f}\"")), "{dir}/{f} missing from CMakeLists.txt");
            }
        }
    }

    #[test]
    fn the_check_catches_a_swapped_field() {
        // The parser must see order: a swapped pair is a different list.
        assert_ne!(fields("float64 upper\nfloat64 lower"), mirrored::<Interval>());
        assert_eq!(fields("# c\nuint8 A=1\nfloat64 lower  # x\nfloat64 upper"), mirrored::<Interval>());
        assert_eq!(rust_type("std_msgs/Header"), "Header");
        assert_eq!(rust_type("Interval[]"), "Vec<Interval>");
    }
}

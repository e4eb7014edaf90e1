"""The rclpy side of tests/topics.rs: a real ROS 2 Jazzy client (Fast DDS) talking to
`linkspace serve`. Each subcommand prints one JSON object on its last stdout line; the Rust
test makes the assertions. Every wait has a timeout.

    topics   --prefix /linkspace/four_bar              every topic of one mechanism
    singular --prefix /linkspace/orthogonal_3r_e ...   singularities, markers, progress of each
    services --node /linkspace --script FILE           service calls listed in a JSON file
    load     --node /linkspace --mechanism four_bar    100 requests in flight from 4 clients
    rosstart --node /lab/linkspace --urdf A --urdf2 B  robot_description by topic, then by parameter
    action   --node /linkspace --script FILE           Solve action goals (feedback, cancel, result)
"""
import argparse
import importlib
import json
import sys
import time

import rclpy
import rclpy.executors
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy

sys.path.insert(0, __file__.rsplit("/", 2)[0] + "/scripts")
from plot_boxes import to_plain  # noqa: E402

from linkspace_msgs.msg import AssemblyMode, BoxSet, Progress, SingularityReport, Settings  # noqa: E402
from rclpy.serialization import serialize_message  # noqa: E402
from linkspace_msgs import srv  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from visualization_msgs.msg import MarkerArray  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402


def latched(depth=1):
    return QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST)


def spin_until(node, done, timeout):
    end = time.monotonic() + timeout
    while not done() and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    return done()


def topics(args):
    node = rclpy.create_node("linkspace_test_topics")
    got = {"configuration_space": [], "markers": [], "assembly_modes": [], "progress": [], "singularities": [], "assembly_mode": []}
    p = args.prefix
    node.create_subscription(BoxSet, f"{p}/configuration_space", got["configuration_space"].append, latched())
    node.create_subscription(MarkerArray, f"{p}/markers", got["markers"].append, latched())
    node.create_subscription(JointState, f"{p}/assembly_modes", got["assembly_modes"].append, latched(64))
    node.create_subscription(AssemblyMode, f"{p}/assembly_mode", got["assembly_mode"].append, latched(64))
    node.create_subscription(Progress, f"{p}/progress", got["progress"].append, latched())
    node.create_subscription(SingularityReport, f"{p}/singularities", got["singularities"].append, latched())
    got["tf_static"] = []
    node.create_subscription(TFMessage, "/tf_static", got["tf_static"].append, latched())
    single = ["configuration_space", "markers", "progress", "singularities", "tf_static"]
    ok = spin_until(node, lambda: all(got[k] for k in single) and len(got["assembly_modes"]) >= args.modes
                    and len(got["assembly_mode"]) >= args.modes, args.timeout)
    # The remaining assembly modes (if any beyond --modes) arrive with the first ones.
    spin_until(node, lambda: False, 0.3)
    out = {"complete": ok, "seen": {k: len(v) for k, v in got.items()}}
    out["configuration_space"] = to_plain(got["configuration_space"][-1]) if got["configuration_space"] else None
    out["markers"] = [{"ns": m.ns, "id": m.id, "type": m.type, "action": m.action, "frame": m.header.frame_id,
                       "position": [m.pose.position.x, m.pose.position.y, m.pose.position.z],
                       "scale": [m.scale.x, m.scale.y, m.scale.z]} for m in got["markers"][-1].markers] if got["markers"] else None
    out["assembly_modes"] = [{"frame": j.header.frame_id, "name": list(j.name), "position": list(j.position)} for j in got["assembly_modes"]]
    out["assembly_mode"] = [to_plain(m) for m in got["assembly_mode"]]
    out["tf_static"] = [{"parent": t.header.frame_id, "child": t.child_frame_id,
                         "translation": [t.transform.translation.x, t.transform.translation.y, t.transform.translation.z],
                         "rotation": [t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w]}
                        for m in got["tf_static"] for t in m.transforms]
    out["tf_static_publishers"] = node.count_publishers("/tf_static")
    out["progress"] = to_plain(got["progress"][-1]) if got["progress"] else None
    s = got["singularities"][-1] if got["singularities"] else None
    out["singularities"] = {"ok": s.ok, "message": s.message, "mechanism": s.mechanism} if s else None
    print(json.dumps(out))


def singular(args):
    """The latched singularity report, markers and progress of each --prefix (3R robots)."""
    node = rclpy.create_node("linkspace_test_singular")
    got = {p: {"singularities": [], "markers": [], "progress": []} for p in args.prefix}
    for p, g in got.items():
        node.create_subscription(SingularityReport, f"{p}/singularities", g["singularities"].append, latched())
        node.create_subscription(MarkerArray, f"{p}/markers", g["markers"].append, latched())
        node.create_subscription(Progress, f"{p}/progress", g["progress"].append, latched())
    ok = spin_until(node, lambda: all(v for g in got.values() for v in g.values()), args.timeout)
    out = {"complete": ok}
    for p, g in got.items():
        out[p] = {
            "singularities": to_plain(g["singularities"][-1]) if g["singularities"] else None,
            "markers": [{"ns": m.ns, "type": m.type, "action": m.action, "frame": m.header.frame_id,
                         "position": [m.pose.position.x, m.pose.position.y, m.pose.position.z]}
                        for m in g["markers"][-1].markers] if g["markers"] else None,
            "progress": to_plain(g["progress"][-1]) if g["progress"] else None,
        }
    print(json.dumps(out))


def convert(value, ros_type):
    """A JSON value as the Python value of a ROS field type ("NaN" strings become floats)."""
    if ros_type.startswith("sequence<"):
        inner = ros_type[len("sequence<"):-1]
        return [convert(v, inner) for v in value]
    if ros_type in ("double", "float"):
        return float(value)
    if ros_type.startswith(("uint", "int")):
        return int(value)
    if ros_type == "boolean":
        return bool(value)
    if ros_type == "string":
        return str(value)
    raise ValueError(f"unexpected field type {ros_type}")


def fill(msg, fields):
    """Sets the fields of a message from a dict; nested messages from dicts or lists."""
    types = msg.get_fields_and_field_types()
    for k, v in fields.items():
        if types[k].startswith("sequence<") and "/" in types[k]:  # a list of messages, from dicts
            package, name = types[k][len("sequence<"):-1].split("/")
            cls = getattr(importlib.import_module(f"{package}.msg"), name)
            items = []
            for item in v:
                m = cls()
                fill(m, item)
                items.append(m)
            setattr(msg, k, items)
        elif types[k].startswith(("linkspace_msgs/", "geometry_msgs/", "trajectory_msgs/")):
            inner = getattr(msg, k)
            if isinstance(v, list):  # a point as [x, y, z]
                v = dict(zip(inner.get_fields_and_field_types(), v))
            fill(inner, v)
        else:
            setattr(msg, k, convert(v, types[k]))


def make_request(kind, fields):
    cls = getattr(srv, kind)
    req = cls.Request()
    fill(req, fields)
    return cls, req


def services(args):
    """Runs the calls of a script: a JSON list of {"service", "type", "request"[, "brief",
    "repeat"]} ("repeat": n makes the call n times in turn, each with its own result) or
    {"subscribe": name} (a fresh subscriber to a latched topic, collected after a settle) or
    {"sleep": seconds} or {"cancel_during": call step, "progress": topic} (the call is sent, the
    first Progress of a run not yet done on that topic gives the run id, Cancel is called with
    it, and then the call's reply is awaited). Service replies are printed in order."""
    script = json.load(open(args.script))
    node = rclpy.create_node("linkspace_test_services")
    clients = {}
    results = []
    warmed = set()
    for step in script:
        if "sleep" in step:
            spin_until(node, lambda: False, step["sleep"])
            results.append({"sleep": step["sleep"]})  # keeps result k at script step k
            continue
        if "subscribe" in step:
            got = []
            msg_type = {"BoxSet": BoxSet, "Progress": Progress, "SingularityReport": SingularityReport}[step.get("type", "BoxSet")]
            node.create_subscription(msg_type, step["subscribe"], got.append, latched())
            spin_until(node, lambda: bool(got), args.timeout)
            spin_until(node, lambda: False, step.get("settle", 0.5))
            results.append({"subscribe": step["subscribe"], "received": [to_plain(m) for m in got]})
            continue
        if "cancel_during" in step:
            results.append(cancel_during(node, step, args.timeout))
            continue
        cls, req = make_request(step["type"], step.get("request", {}))
        name = step["service"]
        if name not in clients:
            clients[name] = node.create_client(cls, name)
        client = clients[name]
        if name not in warmed:
            if not client.wait_for_service(timeout_sec=args.timeout):
                results.append({"service": name, "error": "service not available"})
                continue
            # Fast DDS may lose a request sent right at matching until its next heartbeat
            # (about 3 s): give the match a moment.
            spin_until(node, lambda: False, 0.5)
            warmed.add(name)
        for _ in range(step.get("repeat", 1)):
            results.append(call(node, client, req, step, args.timeout))
    print(json.dumps({"results": results}))


def call(node, client, req, step, timeout):
    """One service call of a script step and its result."""
    name = step["service"]
    t = time.monotonic()
    future = client.call_async(req)
    spin_until(node, future.done, step.get("timeout", timeout))
    if not future.done():
        return {"service": name, "error": "no reply"}
    seconds = time.monotonic() - t
    # "brief": only ok, message and the size (a reply of megabytes, read as JSON, is slow).
    reply = to_plain(future.result()) if not step.get("brief") else {"ok": future.result().ok, "message": future.result().message}
    reply["service"] = name
    reply["seconds"] = seconds
    reply["bytes"] = len(serialize_message(future.result()))
    return reply


def cancel_during(node, step, timeout):
    """Sends a call, cancels its run once its progress is seen, and returns what happened."""
    call = step["cancel_during"]
    cls, req = make_request(call["type"], call.get("request", {}))
    client = node.create_client(cls, call["service"])
    canceller = node.create_client(srv.Cancel, "cancel" if not call["service"].startswith("/") else call["service"].rsplit("/", 1)[0] + "/cancel")
    if not (client.wait_for_service(timeout_sec=timeout) and canceller.wait_for_service(timeout_sec=timeout)):
        return {"error": "service not available"}
    seen = []
    node.create_subscription(Progress, step["progress"], lambda m: seen.append(m) if not m.done else None, 10)
    spin_until(node, lambda: False, 0.5)
    t0 = time.monotonic()
    future = client.call_async(req)
    spin_until(node, lambda: bool(seen) or future.done(), timeout)
    t_progress = time.monotonic() - t0
    if not seen:
        return {"error": "no progress seen before the reply" if future.done() else "no progress seen"}
    progress = to_plain(seen[0])
    cancel_req = srv.Cancel.Request()
    cancel_req.run_id = seen[0].run_id
    cancelled = canceller.call_async(cancel_req)
    spin_until(node, cancelled.done, timeout)
    t_cancel = time.monotonic() - t0
    spin_until(node, future.done, timeout)
    times = {"progress": t_progress, "cancel_reply": t_cancel, "reply": time.monotonic() - t0}
    if not future.done():
        return {"error": "no reply after the cancel", "progress": progress}
    return {"progress": progress, "cancel": to_plain(cancelled.result()) if cancelled.done() else None, "reply": to_plain(future.result()), "seconds": times}


def load(args):
    """Puts `--requests` requests in flight at once from `--clients` nodes, then collects."""
    ex = rclpy.executors.SingleThreadedExecutor()
    nodes = [rclpy.create_node(f"linkspace_load_{k}") for k in range(args.clients)]
    for n in nodes:
        ex.add_node(n)
    base = args.node.rstrip("/")
    kinds = {"classify": srv.Classify, "list_mechanisms": srv.ListMechanisms, "solve": srv.Solve,
             "singularities": srv.Singularities, "inverse_kinematics": srv.InverseKinematics}
    # Every client's reply reader receives the replies to every client of the service (Fast DDS
    # does not filter them by writer), and a keep-last reader drops the oldest when a burst
    # overflows it: with rclpy's default depth of 10, 100 requests in flight from 4 clients
    # lose about 45 replies at the clients (measured), though the node answers all 100. So the
    # depth must cover the requests in flight per service.
    qos = QoSProfile(depth=args.client_depth, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)
    clients = [{k: n.create_client(t, f"{base}/{k}", qos_profile=qos) for k, t in kinds.items()} for n in nodes]
    for cs in clients:
        for c in cs.values():
            if not c.wait_for_service(timeout_sec=args.timeout):
                print(json.dumps({"error": f"{c.srv_name} not available"}))
                return
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        ex.spin_once(timeout_sec=0.05)
    joints = json.loads(args.joints)
    futures = []
    for i in range(args.requests):
        cs = clients[i % args.clients]
        kind = ["classify", "classify", "list_mechanisms", "solve", "singularities", "inverse_kinematics",
                "classify", "solve", "classify", "list_mechanisms"][i % 10]
        if kind == "classify":
            req = srv.Classify.Request(mechanism=args.mechanism if i % 3 else "ghost",
                                       joint_names=list(joints), joint_values=[float(v) + 0.01 * i for v in joints.values()])
        elif kind == "list_mechanisms":
            req = srv.ListMechanisms.Request()
        elif kind == "solve":
            # Long runs (a curve at fine sigma), so that more arrive than the node runs at once.
            req = srv.Solve.Request(mechanism=args.mechanism, wait=0.0,
                                    settings=Settings(sigma=1e-6, rho=0.95, max_boxes=args.solve_boxes, timeout=30.0))
        elif kind == "singularities":
            req = srv.Singularities.Request(mechanism=args.mechanism)
        else:
            req = srv.InverseKinematics.Request(mechanism=args.mechanism, sigma=1e-3)
        futures.append((kind, cs[kind].call_async(req)))
    t0 = time.monotonic()
    end = t0 + args.timeout
    while not all(f.done() for _, f in futures) and time.monotonic() < end:
        ex.spin_once(timeout_sec=0.05)
    replies = []
    for kind, f in futures:
        if not f.done():
            replies.append({"kind": kind, "answered": False})
            continue
        r = f.result()
        if kind == "list_mechanisms":
            replies.append({"kind": kind, "answered": True, "ok": len(r.mechanisms) > 0, "message": ""})
        else:
            replies.append({"kind": kind, "answered": True, "ok": bool(r.ok), "message": r.message,
                            "run_id": int(getattr(r, "run_id", 0))})
    # Cancel the runs that were accepted, so the node is idle again.
    cancel = nodes[0].create_client(srv.Cancel, f"{base}/cancel")
    cancelled = 0
    if cancel.wait_for_service(timeout_sec=args.timeout):
        for r in replies:
            if r.get("run_id"):
                f = cancel.call_async(srv.Cancel.Request(run_id=r["run_id"]))
                end = time.monotonic() + args.timeout
                while not f.done() and time.monotonic() < end:
                    ex.spin_once(timeout_sec=0.05)
                cancelled += int(f.done() and f.result().ok)
    print(json.dumps({"replies": replies, "seconds": time.monotonic() - t0, "cancelled": cancelled}))


def rosstart(args):
    """The node started with --robot-description-topic and no URDF: publishes --urdf latched on
    /robot_description (as robot_state_publisher does), waits for its configuration space, sets
    the robot_description parameter to --urdf2 through the parameter service, waits for that
    one's, reads parameters back, tries bad values, and collects /rosout lines of the node."""
    from std_msgs.msg import String
    from rcl_interfaces.msg import Log, Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import GetParameters, SetParameters
    node = rclpy.create_node("linkspace_test_rosstart")
    out = {}
    logs = []
    node.create_subscription(Log, "/rosout", lambda m: logs.append(m.msg),
                             QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                                        durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST))
    pub = node.create_publisher(String, "/robot_description", latched())
    pub.publish(String(data=open(args.urdf).read()))
    sets = {}

    def watch(prefix):
        sets[prefix] = []
        node.create_subscription(BoxSet, f"{prefix}/configuration_space", sets[prefix].append, latched())
    base = args.node.rstrip("/")
    watch(f"{base}/{args.mechanism}")
    out["first"] = spin_until(node, lambda: bool(sets[f"{base}/{args.mechanism}"]), args.timeout)
    if out["first"]:
        out["first_set"] = {k: to_plain(getattr(sets[f"{base}/{args.mechanism}"][-1], k)) for k in ("mechanism", "clusters", "settings", "header")}
        out["first_set"]["boxes"] = len(sets[f"{base}/{args.mechanism}"][-1].box_status)
    setter = node.create_client(SetParameters, f"{base}/set_parameters")
    getter = node.create_client(GetParameters, f"{base}/get_parameters")
    if not (setter.wait_for_service(timeout_sec=args.timeout) and getter.wait_for_service(timeout_sec=args.timeout)):
        out["error"] = "parameter services not available"
        print(json.dumps(out))
        return
    spin_until(node, lambda: False, 0.5)

    def call(client, req):
        f = client.call_async(req)
        spin_until(node, f.done, args.timeout)
        return f.result() if f.done() else None

    def param(name, kind, value):
        v = ParameterValue(type=kind)
        setattr(v, {ParameterType.PARAMETER_STRING: "string_value", ParameterType.PARAMETER_DOUBLE: "double_value",
                    ParameterType.PARAMETER_INTEGER: "integer_value"}[kind], value)
        return Parameter(name=name, value=v)
    got = call(getter, GetParameters.Request(names=["sigma", "max_runs", "precision", "robot_description"]))
    out["get"] = [to_plain(v) for v in got.values] if got else None
    bad = call(setter, SetParameters.Request(parameters=[param("sigma", ParameterType.PARAMETER_DOUBLE, -1.0),
                                                         param("robot_description", ParameterType.PARAMETER_STRING, "<robot"),
                                                         param("ghost", ParameterType.PARAMETER_DOUBLE, 1.0)]))
    out["bad"] = [to_plain(r) for r in bad.results] if bad else None
    watch(f"{base}/{args.mechanism2}")
    good = call(setter, SetParameters.Request(parameters=[param("robot_description", ParameterType.PARAMETER_STRING, open(args.urdf2).read())]))
    out["good"] = [to_plain(r) for r in good.results] if good else None
    out["second"] = spin_until(node, lambda: bool(sets[f"{base}/{args.mechanism2}"]), args.timeout)
    if out["second"]:
        out["second_set"] = {k: to_plain(getattr(sets[f"{base}/{args.mechanism2}"][-1], k)) for k in ("mechanism", "clusters", "settings")}
    spin_until(node, lambda: any("new robot_description from parameter" in m for m in logs), 3.0)
    out["rosout"] = logs
    print(json.dumps(out))


def action(args):
    """Sends the Solve action goals of a JSON list of {"goal": fields, "cancel": bool} one after
    the other; a goal with "cancel" is cancelled once its first feedback arrives. For each:
    accepted, final status, result, feedback count and the first feedback."""
    from rclpy.action import ActionClient
    from linkspace_msgs.action import Solve as SolveAction
    node = rclpy.create_node("linkspace_test_action")
    client = ActionClient(node, SolveAction, f"{args.node.rstrip('/')}/solve")
    if not client.wait_for_server(timeout_sec=args.timeout):
        print(json.dumps({"error": "action server not available"}))
        return
    spin_until(node, lambda: False, 0.5)
    results = []
    for step in json.load(open(args.script)):
        feedback = []
        goal = SolveAction.Goal()
        fill(goal, step["goal"])
        sent = client.send_goal_async(goal, feedback_callback=lambda m: feedback.append(m.feedback.progress))
        if not spin_until(node, sent.done, args.timeout):
            results.append({"error": "no goal response"})
            continue
        handle = sent.result()
        out = {"accepted": bool(handle.accepted)}
        if step.get("cancel"):
            spin_until(node, lambda: bool(feedback), args.timeout)
            out["feedback_before_cancel"] = len(feedback)
            cancelled = handle.cancel_goal_async()
            spin_until(node, cancelled.done, args.timeout)
            out["cancel_return_code"] = cancelled.result().return_code if cancelled.done() else None
        got = handle.get_result_async()
        if not spin_until(node, got.done, args.timeout):
            out["error"] = "no result"
            results.append(out)
            continue
        out["status"] = got.result().status
        out["result"] = to_plain(got.result().result)
        out["feedback_count"] = len(feedback)
        out["first_feedback"] = to_plain(feedback[0]) if feedback else None
        results.append(out)
    print(json.dumps({"results": results}))


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("topics")
    t.add_argument("--prefix", required=True)
    t.add_argument("--modes", type=int, default=0, help="assembly modes to wait for")
    sg = sub.add_parser("singular")
    sg.add_argument("--prefix", action="append", required=True)
    s = sub.add_parser("services")
    s.add_argument("--script", required=True)
    lo = sub.add_parser("load")
    lo.add_argument("--node", default="/linkspace")
    lo.add_argument("--mechanism", required=True)
    lo.add_argument("--joints", required=True, help="JSON object: a configuration to classify")
    lo.add_argument("--clients", type=int, default=4)
    lo.add_argument("--requests", type=int, default=100)
    lo.add_argument("--solve-boxes", type=int, default=20000)
    lo.add_argument("--client-depth", type=int, default=100, help="history depth of the service clients")
    rs = sub.add_parser("rosstart")
    rs.add_argument("--node", default="/linkspace")
    rs.add_argument("--urdf", required=True)
    rs.add_argument("--mechanism", required=True)
    rs.add_argument("--urdf2", required=True)
    rs.add_argument("--mechanism2", required=True)
    ac = sub.add_parser("action")
    ac.add_argument("--node", default="/linkspace")
    ac.add_argument("--script", required=True)
    for p in (t, sg, s, lo, rs, ac):
        p.add_argument("--timeout", type=float, default=20.0)
    args = ap.parse_args()
    rclpy.init()
    try:
        {"topics": topics, "singular": singular, "services": services, "load": load, "rosstart": rosstart, "action": action}[args.cmd](args)
    finally:
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()

"""A second client of `linkspace serve` for tests/topics.rs: raw DDS through Cyclone DDS's
Python binding (no ROS at all), as rmw_cyclonedds_cpp lays data out. The node must run with
--service-mapping cyclone: requests and replies carry a 16-byte header (client id, sequence
number) before the body. Prints one JSON object on its last line.

    cyclone_client.py --prefix /linkspace/four_bar --node /linkspace --mechanism four_bar
"""
import argparse
import dataclasses
import json
import math
import os
import random
import time
from dataclasses import dataclass

from cyclonedds.core import Qos, Policy
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import sequence, uint8, int32, uint32, int64, uint64, float64
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


# The wire types, field for field as in msgs/ (DDS names: pkg::msg::dds_::Name_).
@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time_
    frame_id: str


@dataclass
class Settings_(IdlStruct, typename="linkspace_msgs::msg::dds_::Settings_"):
    sigma: float64
    rho: float64
    max_boxes: uint64
    timeout: float64


@dataclass
class SolveStats_(IdlStruct, typename="linkspace_msgs::msg::dds_::SolveStats_"):
    processed: uint64
    empty: uint64
    bisected: uint64
    solutions: uint64
    spurious_dropped: uint64
    max_level: uint32
    seconds: float64
    certified: uint64
    post_processing_cut_short: bool


@dataclass
class BoxSet_(IdlStruct, typename="linkspace_msgs::msg::dds_::BoxSet_"):
    header: Header_
    mechanism: str
    analysis: str
    run_id: uint64
    status: uint8
    limit: str
    settings: Settings_
    variable_names: sequence[str]
    dim: uint32
    lower: sequence[float64]
    upper: sequence[float64]
    box_status: sequence[uint8]
    level: sequence[uint32]
    cluster: sequence[int32]
    clusters: uint32
    joint_names: sequence[str]
    joint_lower: sequence[float64]
    joint_upper: sequence[float64]
    fixed_joint_names: sequence[str]
    fixed_joint_values: sequence[float64]
    stats: SolveStats_


@dataclass
class MechanismInfo_(IdlStruct, typename="linkspace_msgs::msg::dds_::MechanismInfo_"):
    name: str
    kind: str
    services: sequence[str]
    free_joints: sequence[str]
    fixed_joint_names: sequence[str]
    fixed_joint_values: sequence[float64]
    state: str
    message: str
    topic_prefix: str


@dataclass
class ListMechanisms_Request_(IdlStruct, typename="linkspace_msgs::srv::dds_::ListMechanisms_Request_"):
    client_guid: uint64
    seq: int64
    structure_needs_at_least_one_member: uint8


@dataclass
class ListMechanisms_Response_(IdlStruct, typename="linkspace_msgs::srv::dds_::ListMechanisms_Response_"):
    client_guid: uint64
    seq: int64
    mechanisms: sequence[MechanismInfo_]


@dataclass
class Classify_Request_(IdlStruct, typename="linkspace_msgs::srv::dds_::Classify_Request_"):
    client_guid: uint64
    seq: int64
    mechanism: str
    joint_names: sequence[str]
    joint_values: sequence[float64]


@dataclass
class Classify_Response_(IdlStruct, typename="linkspace_msgs::srv::dds_::Classify_Response_"):
    client_guid: uint64
    seq: int64
    ok: bool
    message: str
    inside: bool
    component: int32
    components: uint32
    distance: float64
    singular_distance_known: bool
    singular_distance: float64


def plain(x):
    if dataclasses.is_dataclass(x):
        return {f.name: plain(getattr(x, f.name)) for f in dataclasses.fields(x)}
    if isinstance(x, (list, tuple)):
        return [plain(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    return x


def wait_until(done, timeout):
    end = time.monotonic() + timeout
    while not done() and time.monotonic() < end:
        time.sleep(0.01)
    return done()


def call(dp, service, req_type, resp_type, make, timeout):
    """One service call in rmw_cyclonedds's layout; the reply matched by (client id, seq)."""
    qos = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.Durability.Volatile, Policy.History.KeepLast(10))
    w = DataWriter(dp, Topic(dp, f"rq{service}Request", req_type), qos=qos)
    r = DataReader(dp, Topic(dp, f"rr{service}Reply", resp_type), qos=qos)
    if not wait_until(lambda: w.get_publication_matched_status().current_count > 0 and r.get_subscription_matched_status().current_count > 0, timeout):
        return {"error": f"{service}: no match"}
    time.sleep(0.5)  # let the match settle on both sides before the first request
    client, seq = random.getrandbits(63), 1
    w.write(make(client, seq))
    got = []
    def poll():
        got.extend(s for s in r.take(N=10) if s.client_guid == client and s.seq == seq)
        return bool(got)
    if not wait_until(poll, timeout):
        return {"error": f"{service}: no reply"}
    return plain(got[0])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--prefix", required=True)
    ap.add_argument("--node", default="/linkspace")
    ap.add_argument("--mechanism", required=True)
    ap.add_argument("--timeout", type=float, default=20.0)
    args = ap.parse_args()
    dp = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0")))
    latched = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.Durability.TransientLocal, Policy.History.KeepLast(1))
    reader = DataReader(dp, Topic(dp, f"rt{args.prefix}/configuration_space", BoxSet_), qos=latched)
    sets = []
    wait_until(lambda: sets.extend(reader.take(N=10)) or bool(sets), args.timeout)
    out = {"configuration_space": plain(sets[-1]) if sets else None}
    out["list"] = call(dp, f"{args.node}/list_mechanisms", ListMechanisms_Request_, ListMechanisms_Response_,
                       lambda c, s: ListMechanisms_Request_(client_guid=c, seq=s, structure_needs_at_least_one_member=0), args.timeout)
    out["classify_ghost"] = call(dp, f"{args.node}/classify", Classify_Request_, Classify_Response_,
                                 lambda c, s: Classify_Request_(client_guid=c, seq=s, mechanism="ghost", joint_names=[], joint_values=[]), args.timeout)
    print(json.dumps(out))


if __name__ == "__main__":
    main()

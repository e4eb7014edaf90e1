"""Example regression test: the four-bar's two assembly modes at crank 0.5 must match the golden
set by containment. Run it with the ROS environment of the node (launch_notes.md), e.g.

    LINKSPACE_BIN=target/release/linkspace ROS_DOMAIN_ID=52 python -m pytest python/linkspace_testing/examples
"""
import os

from linkspace_testing import assert_matches_golden

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def test_four_bar_assembly_modes_match_the_golden_set(linkspace_node, golden):
    node = linkspace_node([os.path.join(ROOT, "urdf", "four_bar.urdf")], ["--fix", "crank_joint=0.5", "--sigma", "1e-6"])
    got = node.box_set("four_bar")
    assert got["status"] == 0, f"incomplete run: {got['limit']}"
    assert_matches_golden(got, golden("four_bar_crank_0.5.json"), tol=1e-9)

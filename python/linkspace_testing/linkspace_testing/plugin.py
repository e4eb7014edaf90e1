"""pytest fixtures of linkspace_testing (a pytest11 plugin once the package is installed).

    from linkspace_testing import assert_matches_golden

    def test_four_bar(linkspace_node, golden):
        node = linkspace_node(["urdf/four_bar.urdf"], ["--fix", "crank_joint=0.5"])
        assert_matches_golden(node.box_set("four_bar"), golden("four_bar.json"), tol=1e-9)
"""
import os

import pytest

from . import LinkspaceNode, load_golden


@pytest.fixture
def linkspace_node():
    """A factory: `linkspace_node(urdfs, args=(), domain=None)` starts `linkspace serve`; every
    node started is stopped after the test."""
    nodes = []

    def start(urdfs, args=(), domain=None, **kw):
        node = LinkspaceNode(urdfs, args, domain=domain, **kw)
        nodes.append(node)
        return node
    yield start
    for n in nodes:
        n.stop()


@pytest.fixture
def golden(request):
    """`golden(name)`: the golden box set `name` from $LINKSPACE_GOLDEN_DIR, else from a
    `golden/` folder beside the test file."""
    def load(name):
        folder = os.environ.get("LINKSPACE_GOLDEN_DIR") or os.path.join(os.path.dirname(str(request.fspath)), "golden")
        return load_golden(os.path.join(folder, name))
    return load

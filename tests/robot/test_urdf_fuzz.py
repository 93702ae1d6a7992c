"""Property test: a randomly damaged tutorial URDF is either accepted or refused with UrdfError.

Anything else (KeyError, ValueError, RecursionError, ...) escaping read_urdf_xml/check_robot
is a bug: the CLI would report it as an unexpected crash instead of one clear line.
"""

from __future__ import annotations

import copy
import tempfile
from pathlib import Path

from conftest import REPO
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from r2d2_viz.errors import UrdfError
from r2d2_viz.robot.urdf_check import check_robot, read_urdf_xml

TUTORIAL = (REPO / "tests" / "data" / "good" / "r2d2_tutorial.urdf").read_bytes()
N_ELEMENTS = sum(1 for _ in etree.fromstring(TUTORIAL).iter())

NASTY_VALUES = [
    "",
    " ",
    "0",
    "-1",
    "1 2",
    "0 0 0",
    "1 0 0 1",
    "nan",
    "inf -inf nan",
    "1e999",
    "abc",
    "1,2,3",
    "0x10",
    "1_0 0 0",
    "axis",
    "body",
    "head",
    "tilt",
    "swivel",
    "white",
    "revolute",
    "prismatic",
    "continuous",
    "planar",
    "floating",
    "hinge",
    "package://pkg/m.stl",
    "file:///nonexistent/m.dae",
    "../../../etc/passwd",
    "m.stl",
    "ünï cødé / spaces",
    "x" * 300,
]
TAGS = ["link", "joint", "robot", "origin", "axis", "limit", "mimic", "geometry", "box", "mesh", "cone", "x"]
ATTRS = ["name", "type", "link", "xyz", "rpy", "size", "radius", "length", "rgba", "lower", "upper", "joint"]

mutation = st.one_of(
    st.tuples(st.just("drop"), st.integers(1, N_ELEMENTS - 1)),
    st.tuples(st.just("duplicate"), st.integers(1, N_ELEMENTS - 1)),
    st.tuples(st.just("retag"), st.integers(0, N_ELEMENTS - 1), st.sampled_from(TAGS)),
    st.tuples(st.just("drop_attr"), st.integers(0, N_ELEMENTS - 1), st.sampled_from(ATTRS)),
    st.tuples(
        st.just("set_attr"),
        st.integers(0, N_ELEMENTS - 1),
        st.sampled_from(ATTRS),
        st.one_of(st.sampled_from(NASTY_VALUES), st.text(max_size=20)),
    ),
    st.tuples(st.just("move"), st.integers(1, N_ELEMENTS - 1), st.integers(0, N_ELEMENTS - 1)),
)


def _clean(text: str) -> str:
    """lxml refuses attribute values with characters XML cannot hold; keep the fuzzing on the URDF."""
    return "".join(c for c in text if c in "\t\n\r" or (" " <= c <= "\ud7ff") or ("\ue000" <= c <= "\ufffd"))


def mutate(mutations: list[tuple[object, ...]]) -> bytes:
    root = etree.fromstring(TUTORIAL)
    for op, index, *args in mutations:
        nodes = list(root.iter())
        node = nodes[int(str(index)) % len(nodes)]
        parent = node.getparent()
        if op == "drop" and parent is not None:
            parent.remove(node)
        elif op == "duplicate" and parent is not None:
            node.addnext(copy.deepcopy(node))
        elif op == "retag":
            node.tag = str(args[0])
        elif op == "drop_attr":
            node.attrib.pop(str(args[0]), None)
        elif op == "set_attr":
            node.set(str(args[0]), _clean(str(args[1])))
        elif op == "move" and parent is not None:
            target = nodes[int(str(args[0])) % len(nodes)]
            if node not in target.iterancestors() and target is not node:
                parent.remove(node)
                target.append(node)
    data: bytes = etree.tostring(root)
    return data


def must_accept_or_refuse(data: bytes) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "fuzz.urdf"
        path.write_bytes(data)
        try:
            warnings = check_robot(read_urdf_xml(path), source=path.name)
        except UrdfError as exc:
            message = str(exc)
            assert message.startswith("fuzz.urdf: ") and "\n" not in message
        else:
            assert all(w.startswith("fuzz.urdf: ") and "\n" not in w for w in warnings)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(mutation, min_size=1, max_size=6))
def test_mutated_tutorial_is_accepted_or_refused_cleanly(mutations: list[tuple[object, ...]]) -> None:
    must_accept_or_refuse(mutate(mutations))


@settings(max_examples=50, deadline=None)
@given(
    st.integers(0, len(TUTORIAL)),
    st.lists(st.tuples(st.integers(0, len(TUTORIAL) - 1), st.integers(0, 255)), max_size=4),
)
def test_truncated_or_corrupted_bytes_are_accepted_or_refused_cleanly(cut: int, flips: list[tuple[int, int]]) -> None:
    data = bytearray(TUTORIAL)
    for offset, value in flips:
        data[offset] = value
    must_accept_or_refuse(bytes(data[:cut]))

"""MarkerArrays as columns (issue 46, item 3): a batch run decodes a topic's MarkerArrays a block at a time and logs
them as columns, and the recording read back is the one the per-message path makes in the same run (entities,
times, every component, row order at one time): all twelve types (strips and lists coloured per point, text, an
unresolved mesh, triangle lists, arrows by points), both byte orders, an empty namespace, a marker given twice in
one array, an empty frame, DELETE, DELETEALL (of a namespace and of all), lifetimes that run out between messages
and a message that cannot be decoded (said once, counted).

The messages are built and serialised by rosbags (``tests/msgs_build.py``); the per-message path decodes them with
rosbags' deserialiser, the reference here."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import rerun as rr
from msgs_build import TS, T, color, duration, header, marker_msg, pose, quat, vec
from rrd import rows_in_order

from r2d2_viz.msgs import registry
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.viewer import display_feed
from r2d2_viz.viewer.display_feed import DisplayFeed
from r2d2_viz.viewer.notices import Notices

S = 1_000_000_000
T0 = 1_700_000_000 * S
ARRAY = "visualization_msgs/msg/MarkerArray"
P = "Point"


def _array(k: int) -> list[Any]:
    """Seventeen markers: every type, some coloured per point, one given twice."""
    pts = [vec(0, 0, 0, P), vec(k, 1, 0, P), vec(1, k, 0.5, P), vec(2, 2, k, P)]
    per_point = [color(0.1 * i, 0.5, 1.0 - 0.2 * i, 0.9) for i in range(4)]
    return [
        marker_msg(0, ns="arrows", id=1, pose=pose(k, 0, 0, quat(0, 0, 0.3, 0.9)), scale=vec(1.0, 0.1, 0.2)),
        marker_msg(0, ns="arrows", id=2, points=pts[:2], scale=vec(0.05, 0.1, 0.1), color=color(1, 0, 0, 0.5)),
        marker_msg(1, ns="solid", id=1, pose=pose(0, k, 0), scale=vec(0.5, 0.25, 0.125), color=color(0, 0, 1)),
        marker_msg(2, ns="solid", id=2, pose=pose(0, 0, k, quat(0, 0, 0, 0)), scale=vec(0.3, 0.3, 0.3)),
        marker_msg(3, ns="solid", id=3, scale=vec(0.2, 0.4, 1.0), color=color(0.2, 0.8, 0.2, 0.3)),
        marker_msg(4, ns="lines", id=1, points=pts, scale=vec(0.1, 0, 0)),
        marker_msg(4, ns="lines", id=2, points=pts[:1], scale=vec(0.0, 0, 0)),
        marker_msg(4, ns="lines", id=3, points=pts, colors=per_point, scale=vec(0.02, 0, 0)),
        marker_msg(5, ns="lines", id=4, points=pts, colors=per_point),
        marker_msg(6, ns="lists", id=1, points=pts[:3], scale=vec(0.1, 0.1, 0.1)),
        marker_msg(7, ns="lists", id=2, points=pts, colors=per_point, scale=vec(0.2, 0.2, 0.2)),
        marker_msg(8, ns="", id=k % 2, points=pts, scale=vec(0.05, 0.05, 0)),
        marker_msg(8, ns="points", id=1, points=pts[: k % 4], colors=per_point[: k % 4], scale=vec(0.1, 0, 0)),
        marker_msg(9, ns="text", id=1, text=f"ünï {k}", pose=pose(0, 0, k), scale=vec(0, 0, 0.4)),
        marker_msg(10, ns="mesh", id=1, mesh_resource="package://nowhere/a.dae", mesh_use_embedded_materials=k % 2),
        marker_msg(11, ns="tri", id=1, points=pts[:3], colors=per_point[:1]),
        marker_msg(1, ns="solid", id=1, pose=pose(1, k, 0), scale=vec(0.5, 0.25, 0.125), header=header("/map")),
    ]


def _message(k: int) -> tuple[Any, bool]:
    """The k-th array (and whether it is big-endian): plain ones, and among them the cases the block leaves."""
    markers = _array(k)
    if k == 4:
        markers[2] = marker_msg(1, ns="solid", id=1, action=2)  # DELETE
    if k == 6:
        markers.append(marker_msg(0, ns="lines", action=3))  # DELETEALL of a namespace
    if k == 9:
        markers.append(marker_msg(2, ns="life", id=1, lifetime=duration(0, 150_000_000)))  # runs out at k = 10.5
    if k == 13:
        markers[4] = marker_msg(3, ns="solid", id=3, header=header(""))  # no frame: drawn in the fixed one
    if k == 15:
        markers = [marker_msg(0, action=3)]  # DELETEALL
    return T(ARRAY)(markers), k % 5 == 2


def _messages() -> list[TopicMessage]:
    out = []
    for k in range(20):
        msg, big = _message(k)
        data = bytes(TS.serialize_cdr(msg, ARRAY, little_endian=not big))
        if k == 11:
            data = data[: len(data) // 2]  # truncated: said, counted
        out.append(TopicMessage(T0 + k * S // 10, "/markers", ARRAY, data))
    return out


def _record(path: Path, blocks: bool, monkeypatch: pytest.MonkeyPatch) -> tuple[Path, int, list[str]]:
    """The messages through a batch run's display feed (pushed in two windows) into ``path``; how many went
    through the per-message decoder, and the warnings said."""
    rec = rr.RecordingStream(f"test_marker_columns_{blocks}")
    rec.save(path)
    calls: list[int] = []
    original = registry.DECODERS[ARRAY]

    def counted(data: Any, options: Any) -> Any:
        calls.append(1)
        return original(data, options)

    with monkeypatch.context() as patch:
        patch.setitem(registry.DECODERS, ARRAY, counted)
        if not blocks:  # today's path: every message decoded and logged alone
            patch.setattr(display_feed, "BLOCK_DECODERS", {})
        said: list[str] = []
        notices = Notices(rec, warn=said.append, clock="timestamp", at_ns=T0)
        feed = DisplayFeed(notices, clock="timestamp", fixed_frame="odom", topics={"/markers": ARRAY}, hold=True)
        messages = _messages()
        feed.push(messages)
        feed.until(messages[8].time_ns)
        feed.until(None)
        feed.finish()
    rec.flush()
    rr.disconnect(recording=rec)
    return path, len(calls), said


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[bool, tuple[Path, int, list[str]]]:
    folder = tmp_path_factory.mktemp("marker_columns")
    with pytest.MonkeyPatch.context() as patch:
        return {blocks: _record(folder / f"{blocks}.rrd", blocks, patch) for blocks in (False, True)}


def test_the_recording_is_the_per_message_one(recorded: dict[bool, tuple[Path, int, list[str]]]) -> None:
    before, after = rows_in_order(recorded[False][0], ("/markers",)), rows_in_order(recorded[True][0], ("/markers",))
    assert sorted(after) == sorted(before)
    for entity in before:
        assert after[entity] == before[entity], entity
    assert len(before["/markers/solid/1"]) > 10  # drawn, deleted, drawn again
    assert [t for t, row in before["/markers/life/1"] if "Clear:is_recursive" in row] == [
        T0 + 9 * S // 10 + 150_000_000
    ]


def test_only_the_messages_the_block_leaves_are_decoded_alone(
    recorded: dict[bool, tuple[Path, int, list[str]]],
) -> None:
    # 20 messages: today all 20 decoded alone; with blocks, the DELETE (4), the namespace's DELETEALL (6), the
    # lifetime (9) and the messages while it runs (10, 11: truncated, 12: its expiry is cleared there), the empty
    # frame (13) and the DELETEALL (15)
    assert recorded[False][1] == 20
    assert recorded[True][1] == 8


def test_the_problems_are_said_as_before(recorded: dict[bool, tuple[Path, int, list[str]]]) -> None:
    said = recorded[True][2]
    assert said == recorded[False][2]
    assert sum("/markers" in line and "cannot be shown" in line for line in said) == 1
    assert sum("empty frame_id" in line for line in said) == 1

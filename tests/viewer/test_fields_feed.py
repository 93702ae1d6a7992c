"""Every other topic of a bag in the recording, as rosbags' deserializer reads it (the golden source): a lab's own
type whose definition is only in the bag, a controller's state; and ``--plot`` series equal to the same field —
through the real CLI, read back with Rerun's own reader (tests/rrd.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import cli
from fieldbags import BATTERY, STATE, expected_fields, messages, store, write
from rerun.chunk import RrdReader
from rrd import Rows, read_recording

from r2d2_viz.viewer.fields_feed import CHUNK_ROWS

N = 120
PLOTS = ("/odom.twist.twist.linear.x", "/arm_controller/state.error.positions[0]")


@pytest.fixture(scope="module", params=["mcap", "sqlite3"])
def recorded(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, str]:
    tmp = tmp_path_factory.mktemp(request.param)
    bag = write(tmp / "bag", messages(N), storage=request.param)
    out = tmp / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), "--plot", *PLOTS, "--plot", "/battery.voltage", cwd=tmp)
    assert result.returncode == 0, result.stderr
    return read_recording(out), result.stderr


def _golden(topic: str, msgtype: str, n: int = N) -> list[tuple[int, dict]]:
    ts = store()
    return [
        (t, expected_fields(ts, ts.deserialize_cdr(d, msgtype), msgtype)) for top, t, d in messages(n) if top == topic
    ]


@pytest.mark.parametrize(("topic", "msgtype"), [("/battery", BATTERY), ("/arm_controller/state", STATE)])
def test_the_recording_holds_every_field_of_every_message(recorded: tuple[dict, str], topic: str, msgtype: str) -> None:
    recording, _ = recorded
    _assert_every_field(recording[f"/topics{topic}"], topic, msgtype, N)


def test_a_batch_run_sends_a_topics_fields_in_chunks_of_thousands_of_messages(tmp_path: Path) -> None:
    """Issue 38: the fields went to Rerun a ``send_columns`` per block and per layout in it (60 chunks for 3,000
    batteries whose strings and arrays change length, a few hundred rows each), which cost Rerun more to encode and
    write than the values. A batch run holds a topic's rows until it has ``CHUNK_ROWS`` (or ``CHUNK_BYTES``) of
    them; the recording holds the same values at the same times (rosbags' deserializer: the golden source)."""
    n = 3000
    bag = write(tmp_path / "bag", messages(n))
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    reader = RrdReader(out)
    chunks: dict[str, int] = {}
    for chunk in reader.stream(store=reader.recordings()[0]):
        chunks[chunk.entity_path] = chunks.get(chunk.entity_path, 0) + 1
    assert chunks["/topics/battery"] <= -(-n // CHUNK_ROWS), chunks
    recording = read_recording(out)
    for topic, msgtype in (("/battery", BATTERY), ("/arm_controller/state", STATE)):
        _assert_every_field(recording[f"/topics{topic}"], topic, msgtype, n)


def _assert_every_field(rows: Rows, topic: str, msgtype: str, n: int) -> None:
    """Each message's fields in its row, as rosbags deserialises them; what a message lacks is empty or null."""
    assert len(rows.times) == n
    for k, (t, want) in enumerate(_golden(topic, msgtype, n)):
        at = rows.times.index(t)
        got = {
            name.split(":", 1)[1]: values[at][0]
            for name, values in rows.temporal.items()
            if name.startswith(msgtype + ":") and values[at]  # None or empty: not in this message (cleared)
        }
        if want.get("blob.len") == 0:  # an empty blob: its length, no min or max
            got = {n: v for n, v in got.items() if n not in ("blob.min", "blob.max")}
        assert set(got) == set(want), (k, set(got) ^ set(want))
        for name, value in want.items():
            assert got[name] == (value.item() if isinstance(value, np.generic) else value), (k, name)


def test_each_plot_is_the_field_rosbags_decodes(recorded: tuple[dict, str]) -> None:
    recording, stderr = recorded
    ts = store()
    fields = [
        ("/odom", "nav_msgs/msg/Odometry", "twist.twist.linear.x"),
        ("/arm_controller/state", STATE, "error.positions[0]"),
    ]
    for view, (topic, msgtype, field) in [(0, f) for f in fields] + [(1, ("/battery", BATTERY, "voltage"))]:
        text = f"{topic}.{field}"
        [entity] = [
            e
            for e in recording
            if e.startswith(f"/plot/{view}/")
            and e.endswith(text.replace("/", "\\/").replace("[", "\\[").replace("]", "\\]"))
        ]
        rows = recording[entity]
        want = [
            (t, expected_fields(ts, ts.deserialize_cdr(d, msgtype), msgtype)[field])
            for top, t, d in messages(N)
            if top == topic
        ]
        assert rows.times == [t for t, _ in want]
        assert [v[0] for v in rows.temporal["Scalars:scalars"]] == pytest.approx([float(v) for _, v in want])
        assert rows.static["SeriesLines:names"] == [[text]]
    assert "/topics/odom" not in recording  # a display draws odometry: its fields only where --plot asks
    assert "cannot be decoded" not in stderr, stderr


def test_a_plot_path_that_names_nothing_is_one_line_naming_the_fields(tmp_path: Path) -> None:
    bag = write(tmp_path / "bag", messages(3))
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), "--plot", "/battery.voltag", cwd=tmp_path)
    assert result.returncode == 2 and not out.exists()
    [line] = result.stderr.splitlines()
    assert line.startswith(
        "error: --plot /battery.voltag: my_msgs/msg/Battery has no field voltag there; "
        "/battery's fields: header.stamp.sec, "
    ), line
    assert "voltage" in line and len(line) <= 300 and "Traceback" not in result.stderr
    motion = cli("--motion", "circle", "--save", str(out), "--plot", "/odom.twist.twist.linear.x", cwd=tmp_path)
    assert motion.returncode == 2 and not out.exists()
    assert motion.stderr.startswith("error: --plot plots a bag's fields")


def test_a_definition_that_does_not_parse_is_one_line_and_the_rest_is_shown(tmp_path: Path) -> None:
    bag = write(tmp_path / "bag", messages(5))
    [mcap] = bag.glob("*.mcap")
    data = mcap.read_bytes()
    assert data.count(b"float32 voltage") == 2  # the schema, in the data section and the summary
    mcap.write_bytes(data.replace(b"float32 voltage", b"floatXX voltage"))
    out = tmp_path / "out.rrd"
    result = cli("--bag", str(bag), "--save", str(out), cwd=tmp_path)
    assert result.returncode == 0 and "Traceback" not in result.stderr, result.stderr
    [line] = [x for x in result.stderr.splitlines() if "/battery" in x]
    assert len(line) - len(str(tmp_path)) <= 300, line
    assert (
        "1 topic that cannot be decoded, not shown: /battery; my_msgs/msg/Battery: its message "
        "definition cannot be used" in line
    )
    recording = read_recording(out)
    assert "/topics/battery" not in recording and len(recording["/topics/arm_controller/state"].times) == 5


def test_a_live_graphs_fields_are_logged_as_they_arrive(tmp_path: Path) -> None:
    """LiveFields (what --ros does with a topic no display draws): sensor_msgs/Joy samples, read back against
    rosbags' deserializer (Jazzy's types, as the graph's)."""
    import rerun as rr

    from r2d2_viz.msgs.typestore import typestore
    from r2d2_viz.sources.bag_displays import TopicMessage
    from r2d2_viz.viewer.fields_feed import LiveFields

    ts = typestore("jazzy")
    T = ts.types
    joy = "sensor_msgs/msg/Joy"
    out = tmp_path / "live.rrd"
    rec = rr.RecordingStream("test_live_fields")
    rec.save(str(out))
    fields = LiveFields(rec, ts)
    sent = []
    for batch in range(3):  # three polls of two samples each
        messages = []
        for i in range(2):
            k = 2 * batch + i
            header = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](k, 0), "joy")
            raw = bytes(
                ts.serialize_cdr(T[joy](header, np.array([0.1 * k, -1.0], np.float32), np.array([k], np.int32)), joy)
            )
            messages.append(TopicMessage(1_000_000_000 * (k + 1), "/joy", joy, raw))
            sent.append(raw)
        fields.log(messages)
    rec.flush()
    rec.disconnect()
    rows = read_recording(out)["/topics/joy"]
    assert rows.times == [1_000_000_000 * (k + 1) for k in range(6)]
    for k, raw in enumerate(sent):
        want = expected_fields(ts, ts.deserialize_cdr(raw, joy), joy)
        got = {n.split(":", 1)[1]: v[k][0] for n, v in rows.temporal.items() if v[k] is not None}
        assert set(got) == set(want) and all(
            got[n] == pytest.approx(float(want[n]) if not isinstance(want[n], str) else want[n]) for n in want
        )


def test_with_header_time_rows_go_to_their_header_stamps_in_order(tmp_path: Path) -> None:
    """``--time header``: two messages received in one order, stamped in the other (values by hand)."""
    import rerun as rr

    from r2d2_viz.msgs.generic.fields import Columns
    from r2d2_viz.viewer.fields_feed import FieldsFeed

    out = tmp_path / "header.rrd"
    rec = rr.RecordingStream("test_header_time")
    rec.save(str(out))
    feed = FieldsFeed(rec, clock="timestamp", shown={"/x": "my_msgs/msg/X"}, header_time=True)
    numbers = {
        "header.stamp.sec": np.array([5, 3], dtype=np.int32),
        "header.stamp.nanosec": np.array([7, 0], dtype=np.uint32),
        "value": np.array([1.0, 2.0]),
    }
    feed.push([("/x", Columns(np.array([10, 20], dtype=np.int64), numbers))])
    assert feed.next_time_ns == 3_000_000_000
    feed.until(4_000_000_000)  # the earlier stamp only
    assert feed.next_time_ns == 5_000_000_007
    feed.until(None)
    rec.flush()
    rec.disconnect()
    rows = read_recording(out)["/topics/x"]
    assert rows.times == [3_000_000_000, 5_000_000_007]
    assert rows.temporal["my_msgs/msg/X:value"] == [[2.0], [1.0]]


def test_ros1_header_seq_is_a_field_and_plottable(tmp_path: Path) -> None:
    """A ROS 1 bag written with rosbags: ``/ref`` (``sensor_msgs/TimeReference``, no display draws it) shows
    ``header.seq`` among its fields, as rosbags' ``deserialize_ros1`` gives it (0, 1, 2, 4, 5, 9, 10: gaps where
    messages were lost), and ``--plot /ref.header.seq`` plots it; a type without a header has none."""
    import seqbags

    path = seqbags.write(tmp_path / "seq.bag")
    want = seqbags.seqs(path, "/ref")
    assert [s for _, s in want] == list(seqbags.REF_SEQ)
    out = tmp_path / "seq.rrd"
    done = cli("--bag", str(path), "--save", str(out), "--plot", "/ref.header.seq", "--plot", "/temp.header.seq")
    assert done.returncode == 0, done.stderr
    recording = read_recording(out)
    rows = recording["/topics/ref"]
    assert rows.times == [t for t, _ in want]
    assert [v[0] for v in rows.temporal["sensor_msgs/msg/TimeReference:header.seq"]] == [s for _, s in want]
    plot = recording["/plot/0/\\/ref.header.seq"]
    assert [v[0] for v in plot.temporal["Scalars:scalars"]] == pytest.approx([float(s) for _, s in want])
    temp = seqbags.seqs(path, "/temp")  # a display draws /temp: its seq only where --plot asks
    plot = recording["/plot/1/\\/temp.header.seq"]
    assert plot.times == [t for t, _ in temp]
    assert [v[0] for v in plot.temporal["Scalars:scalars"]] == pytest.approx([float(s) for _, s in temp])
    assert "/topics/value" not in recording or not any("seq" in k for k in recording["/topics/value"].temporal)


@pytest.mark.parametrize("gather", [False, True])
def test_rows_held_across_blocks_keep_what_was_cleared_and_what_was_not_known_yet(tmp_path: Path, gather: bool) -> None:
    """Issue 38's chunks hold the rows of several blocks and layouts (times interleaved): each row must still show
    what its own message had — a field an earlier message had and this one lacks is empty (cleared, issue 37), a
    field first seen in a later block is nothing (null) before — as a chunk per block showed them. Values by hand."""
    import rerun as rr

    from r2d2_viz.msgs.generic.fields import Columns
    from r2d2_viz.viewer.fields_feed import FieldsFeed

    out = tmp_path / "out.rrd"
    rec = rr.RecordingStream("test_held_rows")
    rec.save(str(out))
    feed = FieldsFeed(rec, clock="timestamp", shown={"/x": "my_msgs/msg/X"}, gather=gather)
    t = 1_700_000_000_000_000_000
    blocks = [
        [  # two layouts of one block, their times interleaved
            Columns(np.array([t + 10, t + 30]), {"a": np.array([1.0, 3.0])}),
            Columns(np.array([t + 20]), {"a": np.array([2.0]), "b": np.array([5], dtype=np.int32)}),
        ],
        [
            Columns(np.array([t + 40]), {"a": np.array([4.0])}),
            Columns(np.array([t + 50]), texts={"c": np.array(["hi"], dtype=object)}),
        ],
    ]
    for block in blocks:
        feed.push([("/x", c) for c in block])
        feed.until(t + 50)
    feed.finish(lambda line: None)
    rec.flush()
    rec.disconnect()
    rows = read_recording(out)["/topics/x"]
    got = [{n.split(":", 1)[1]: v[i] for n, v in sorted(rows.temporal.items())} for i in range(len(rows.times))]
    assert [x - t for x in rows.times] == [10, 20, 30, 40, 50]
    assert got == [
        {"a": [1.0], "b": [], "c": None},
        {"a": [2.0], "b": [5], "c": None},
        {"a": [3.0], "b": [], "c": None},
        {"a": [4.0], "b": [], "c": []},
        {"a": [], "b": [], "c": ["hi"]},
    ]


def test_what_a_batch_run_holds_is_bounded_over_all_topics(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Many slow topics each under a chunk's rows would together hold their whole bag: past ``HELD_BYTES`` all are
    sent, and every row still reaches the recording once."""
    import rerun as rr

    from r2d2_viz.msgs.generic.fields import Columns
    from r2d2_viz.viewer import fields_feed

    monkeypatch.setattr(fields_feed, "HELD_BYTES", 1000)
    out = tmp_path / "out.rrd"
    rec = rr.RecordingStream("test_held_bound")
    rec.save(str(out))
    topics = {f"/t{k}": "my_msgs/msg/X" for k in range(30)}
    feed = fields_feed.FieldsFeed(rec, clock="timestamp", shown=topics, gather=True)
    t = 1_700_000_000_000_000_000
    most = 0
    for i in range(20):
        feed.push([(topic, Columns(np.array([t + i]), {"a": np.array([float(i)])})) for topic in topics])
        feed.until(t + i)
        most = max(most, feed.held_bytes)
    feed.finish(lambda line: None)
    rec.flush()
    rec.disconnect()
    assert most <= 1000 and feed.held_bytes == 0
    recording = read_recording(out)
    for topic in topics:
        assert recording[f"/topics{topic}"].temporal["my_msgs/msg/X:a"] == [[float(i)] for i in range(20)]

"""Runs of images, points and pinholes sent as columns (issue 38: logged one ``rec.log`` per message, their
archetypes built per message, they cost more than reading the bag): read back with Rerun's reader, every row is
what the per-message path (:func:`r2d2_viz.viewer.displays.log_decoded`) logs, and the pixels are the message's
own bytes (written by hand below)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from rrd import read_recording

from r2d2_viz.msgs import shapes
from r2d2_viz.msgs.shapes import Decoded, Pose
from r2d2_viz.sources.bag_displays import TopicMessage
from r2d2_viz.viewer.blocks.display_columns import RUN_BYTES, ColumnRuns, columnable
from r2d2_viz.viewer.displays import log_decoded

S = 1_000_000_000
RGB = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3)  # 2 rows of 3 pixels, bytes 0..17
MONO16 = np.array([[1, 2], [0x0102, 0xFFFF]], dtype=np.uint16)
K = np.array([[500.0, 0, 320], [0, 505, 240], [0, 0, 1]])


def _messages() -> list[tuple[str, Decoded]]:
    turned = Pose((1.0, 2.0, 3.0), (0.0, 0.0, 0.6, 0.8))
    return [
        ("/cam/image", Decoded("cam", 0, (shapes.Image(RGB, "RGB", "rgb8"),))),
        ("/depth", Decoded("cam", 0, (shapes.Image(MONO16, "L", "16UC1"),))),
        ("/cam/image/compressed", Decoded("cam", 0, (shapes.CompressedImage(b"\xff\xd8jpeg", "image/jpeg"),))),
        ("/cloud", Decoded("lidar", 0, (shapes.Points(np.ones((3, 3), np.float32), _rgba(3), 0.02),))),
        ("/cloud", Decoded("lidar", 0, (shapes.Points(np.zeros((0, 3), np.float32), _rgba(1), 0.05, turned),))),
        ("/cam/image", Decoded("cam2", 0, (shapes.Image(RGB[::-1], "BGR", "bgr8"),))),  # a strided view
        ("/cam/info", Decoded("cam", 0, (shapes.Pinhole(K, 640, 480),))),
        ("/cloud", Decoded("lidar", 0, (shapes.Points(np.full((2, 3), 7, np.float32), _rgba(2), 0.02),))),
        ("/odom/7", Decoded("odom", 0, (shapes.Arrows(_xyz(1, 0), _xyz(1, 1), _rgba(1), 0.01, turned),))),  # a slot
        ("/odom/8", Decoded("odom", 0, (shapes.Arrows(_xyz(2, 5), _xyz(2, 6), _rgba(2), 0.02),))),
    ]


def _xyz(n: int, at: float) -> np.ndarray:
    return np.arange(n * 3, dtype=np.float32).reshape(n, 3) + at


def _rgba(n: int) -> np.ndarray:
    return (np.arange(n * 4, dtype=np.uint8).reshape(n, 4) * 13).astype(np.uint8)


CAMERA = {"/cam/info": ("/cam/image", "/cam/image/compressed")}


def _record(path: Path, columns: bool, data: bytes = b"", sent: list[int] | None = None, *, hold: bool = False) -> None:
    """Every message logged one by one, or (``columns``) added to runs, each with ``data`` as its bytes and a window
    ending after it (``hold``: a batch run's runs, kept across windows); ``sent``: after each message, how many runs
    are held (sent ones are gone)."""
    rec = rr.RecordingStream("test_display_columns")
    rec.save(path)
    runs = ColumnRuns(rec, "time", "timestamp", hold=hold)
    for i, (topic, decoded) in enumerate(_messages()):
        time_ns = (i + 1) * S
        assert columnable(decoded)
        if columns:
            runs.add(TopicMessage(time_ns, topic, "", data, decoded=decoded), topic, CAMERA.get(topic, ()))
            if hold:
                runs.interrupt()  # the end of a window: a live run sends its runs here, a batch run keeps them
            if sent is not None:
                sent.append(len(runs.runs))
            continue
        for entity in (topic, *CAMERA.get(topic, ())):
            log_decoded(rec, entity, decoded, timeline="time", time_ns=time_ns, clock="timestamp")
    runs.interrupt(everything=True)
    rec.flush()
    rec.disconnect()


@pytest.mark.parametrize("held", ["whole", "bounded", "across windows"])
def test_a_run_sent_as_columns_is_what_logging_each_message_gives(tmp_path: Path, held: str) -> None:
    _record(tmp_path / "each.rrd", columns=False)
    held_runs: list[int] = []
    # bounded: each message's bytes are a run's limit (RUN_BYTES), so every run goes out as soon as a message joins
    # it (a window's scans in one run raised a --topics run's peak by ~60 MB); the recording must not change
    data = b"\0" * (RUN_BYTES if held == "bounded" else 1)
    _record(tmp_path / "runs.rrd", columns=True, data=data, sent=held_runs, hold=held == "across windows")
    expected = {
        "whole": [1, 2, 3, 4, 4, 4, 5, 5, 6, 7],
        "bounded": [0] * 10,
        "across windows": [0, 0, 0, 1, 1, 1, 4, 4, 5, 6],  # images go at each window's end (views of their bytes)
    }
    assert held_runs == expected[held]
    each, runs = read_recording(tmp_path / "each.rrd"), read_recording(tmp_path / "runs.rrd")
    assert set(runs) - {"/__properties"} == set(each) - {"/__properties"}
    for entity in set(each) - {"/__properties"}:
        assert runs[entity].times == each[entity].times, entity
        assert dict(runs[entity].temporal) == dict(each[entity].temporal), entity
    image = runs["/cam/image"]
    # the pixels as the message held them, row by row (by hand: bytes 0..17; the second one's rows swapped)
    buffers = [b for b in image.temporal["Image:buffer"] if b is not None]
    assert buffers == [[list(range(18))], [[*range(9, 18), *range(9)]]]
    depth = runs["/depth"].temporal["Image:buffer"][0][0]
    assert depth == list(MONO16.astype("<u2").tobytes())  # little-endian words: 01 00 02 00 02 01 ff ff
    cloud = runs["/cloud"]
    assert [len(p) for p in cloud.temporal["Points3D:positions"]] == [3, 0, 2]
    assert cloud.temporal["InstancePoses3D:quaternions"][1] == [[0.0, 0.0, 0.6000000238418579, 0.800000011920929]]
    assert runs["/odom/8"].temporal["Arrows3D:origins"] == [[[5, 6, 7], [8, 9, 10]]]
    # the pinhole on the camera's image entities too, each naming its own image plane
    assert runs["/cam/image"].temporal["Pinhole:child_frame"][2] == ["/cam/image#image"]


def test_what_cannot_join_a_run() -> None:
    pinhole = Decoded("cam", 0, (shapes.Pinhole(K, 640, 480),))
    assert columnable(pinhole) and not columnable(pinhole, first=True)  # a camera's first: from the run's start
    assert not columnable(Decoded("", 0, (shapes.Image(RGB, "RGB", "rgb8"),)))  # no frame: said, then the fixed one
    two = (shapes.Image(RGB, "RGB", "rgb8"), shapes.Image(RGB, "RGB", "rgb8"))
    assert not columnable(Decoded("cam", 0, two))
    assert not columnable(Decoded("map", 0, (shapes.Text("hi", (0.0, 0.0, 0.0), 0.1, (1, 1, 1, 1)),)))


def test_a_batch_run_holds_no_view_of_a_messages_bytes_across_windows(tmp_path: Path) -> None:
    """A .db3's blocks are anonymous memory: an item that is a view of its message's bytes (an image; points read
    straight from the bytes) would keep its whole block alive while held. Held across windows: only what owns its
    arrays (found with a .db3 sensor bag whose peak went from 252 MB to 3,087 MB, the whole bag, when images were
    held too)."""
    rec = rr.RecordingStream("test_display_columns_pins")
    rec.save(tmp_path / "pins.rrd")
    runs = ColumnRuns(rec, "time", "timestamp", hold=True)
    block = bytearray(np.arange(6, dtype=np.float32).tobytes())  # stands for a block read from a bag
    viewed = np.frombuffer(block, dtype=np.float32).reshape(2, 3)
    items = {
        "/image": shapes.Image(np.frombuffer(block, np.uint8).reshape(2, 3, 4)[..., :3], "RGB", "rgb8"),
        "/viewed": shapes.Points(viewed, _rgba(2), 0.02),
        "/owned": shapes.Points(viewed.copy(), _rgba(2), 0.02),
        "/arrow": shapes.Arrows(_xyz(1, 0), _xyz(1, 1), _rgba(1), 0.01),
    }
    for i, (topic, item) in enumerate(items.items()):
        runs.add(TopicMessage((i + 1) * S, topic, "", bytes(block), decoded=Decoded("f", 0, (item,))), topic)
    runs.interrupt()  # the end of a window
    assert set(runs.runs) == {"/owned", "/arrow"}
    runs.interrupt(everything=True)
    assert runs.runs == {} and runs.held == 0
    rec.flush()
    rec.disconnect()


def test_a_run_of_one_camera_model_is_built_once_per_length_and_is_what_rerun_converts(monkeypatch) -> None:
    """Issue 48: a camera's pinhole went through Rerun's ``Pinhole.columns`` for every run on three entities. A run
    of one model is now built once per model and length; its columns are Rerun's own converter's for those rows
    (``_pinhole_columns``: ``rr.Pinhole.columns``), a run of two models is converted row by row as before."""
    from r2d2_viz.viewer.blocks import display_columns as dc

    other = shapes.Pinhole(K * 2, 320, 240)
    calls: list[int] = []
    convert = rr.Pinhole.columns
    monkeypatch.setattr(rr.Pinhole, "columns", lambda **kw: calls.append(len(kw["parent_frame"])) or convert(**kw))
    dc._same_pinholes.cache_clear()
    model = [shapes.Pinhole(K.copy(), 640, 480) for _ in range(3)]

    def arrays(columns: list) -> list:
        return [(d.component, a.to_pylist()) for d, a in columns]

    expected = arrays(dc._pinhole_columns("/cam/info", model, ["cam"] * 3))
    calls.clear()
    assert arrays(dc._pinholes("/cam/info", model, ["cam"] * 3)) == expected and calls == [3]
    assert arrays(dc._pinholes("/cam/info", [shapes.Pinhole(K.copy(), 640, 480) for _ in range(3)], ["cam"] * 3)) == (
        expected
    )
    assert calls == [3]  # the same model and length: not converted again
    assert arrays(dc._pinholes("/cam/info", model[:2], ["cam"] * 2)) == [(c, v[:2]) for c, v in expected]
    mixed = [model[0], other]
    assert arrays(dc._pinholes("/cam/info", mixed, ["cam", "cam"])) == arrays(
        dc._pinhole_columns("/cam/info", mixed, ["cam", "cam"])
    )
    assert [v for c, v in arrays(dc._pinholes("/cam/info", mixed, ["cam", "cam"])) if "resolution" in c] == [
        [[[640.0, 480.0]], [[320.0, 240.0]]]  # a list of one resolution a row
    ]


def test_a_run_of_encoded_images_goes_in_one_call_per_media_type_with_the_rows_logging_gives(
    tmp_path: Path, monkeypatch
) -> None:
    """Issue 48: a call (and a chunk) per JPEG. A run of them now goes in one call per media type; read back, the
    rows are those one ``rec.log`` per message gives (the bytes written by hand below)."""
    from r2d2_viz.viewer.blocks import display_columns as dc

    images = [
        shapes.CompressedImage(b"\xff\xd8one", "image/jpeg"),
        shapes.CompressedImage(b"\x89PNG", "image/png"),
        shapes.CompressedImage(b"\xff\xd8second!", "image/jpeg"),
        shapes.CompressedImage(b"", "image/jpeg"),
    ]
    calls: list[int] = []
    send = dc.send
    monkeypatch.setattr(
        dc,
        "send",
        lambda rec, entity, timeline, times, columns: (
            calls.append(len(times)) or send(rec, entity, timeline, times, columns)
        ),
    )
    for name, columns in (("each", False), ("run", True)):
        rec = rr.RecordingStream("test_display_columns_jpegs")
        rec.save(tmp_path / f"{name}.rrd")
        runs = ColumnRuns(rec, "time", "timestamp")
        for i, image in enumerate(images):
            decoded = Decoded("cam", 0, (image,))
            if columns:
                runs.add(TopicMessage((i + 1) * S, "/jpeg", "", b"x", decoded=decoded), "/jpeg")
            else:
                log_decoded(rec, "/jpeg", decoded, timeline="time", time_ns=(i + 1) * S, clock="timestamp")
        runs.interrupt(everything=True)
        rec.flush()
        rec.disconnect()
    assert calls == [3, 1]  # the JPEGs in one call, the PNG in another
    each, run = read_recording(tmp_path / "each.rrd")["/jpeg"], read_recording(tmp_path / "run.rrd")["/jpeg"]
    assert run.times == each.times and dict(run.temporal) == dict(each.temporal)
    blobs = [b for b in run.temporal["EncodedImage:blob"] if b is not None]
    assert blobs == [[list(b"\xff\xd8one")], [list(b"\x89PNG")], [list(b"\xff\xd8second!")], [[]]]

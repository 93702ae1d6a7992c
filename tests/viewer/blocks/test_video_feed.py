"""The video feed's keyframe rule, by hand: samples before a stream's first keyframe are skipped and counted, the
codec is logged once before the first sample shown, and a stream that never had a keyframe is said to have none."""

from __future__ import annotations

import rerun as rr

from r2d2_viz.msgs.shapes import Decoded, VideoSample
from r2d2_viz.viewer.blocks.video_feed import VideoFeed


def _sample(keyframe: bool) -> Decoded:
    return Decoded("cam", 0, (VideoSample("H264", b"\x00\x00\x00\x01", keyframe),))


def test_samples_before_the_first_keyframe_are_skipped_and_said_once() -> None:
    rec = rr.RecordingStream("test", recording_id="video-feed")
    feed = VideoFeed(None)
    shown = [feed.ready(rec, "/a", _sample(k)) for k in (False, False, True, False)]
    assert shown == [False, False, True, True]
    assert not feed.ready(rec, "/b", _sample(False))
    said = dict(feed.finish())
    assert said == {
        "/a": "the video starts without a keyframe: 2 samples skipped up to the first one",
        "/b": "the video has no keyframe: its 1 samples cannot be shown",
    }


def test_without_an_encoder_a_raw_image_is_left_as_it_is() -> None:
    decoded = _sample(True)
    assert VideoFeed(None).encode("/a", 0, decoded) is decoded

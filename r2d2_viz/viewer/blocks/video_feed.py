"""Cameras as Rerun ``VideoStream`` s (``--video``): raw 8-bit images encoded as they are read (one encoder per
topic), compressed samples passed through, each stream shown from its first keyframe (the samples before it
skipped, said once at the end)."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import rerun as rr

from r2d2_viz.msgs.images import EncoderName, VideoEncoder
from r2d2_viz.msgs.shapes import Decoded, Image, MarkerOp, VideoSample
from r2d2_viz.msgs.typestore import MsgError


class VideoFeed:
    """``encoder``: the codec raw images become (None: they stay lossless ``Image`` s); ``live``: low-latency
    rate control and a keyframe a second (two in a recording)."""

    def __init__(self, encoder: EncoderName | None, *, live: bool = False) -> None:
        self.encoder, self.live = encoder, live
        self._encoders: dict[str, VideoEncoder] = {}
        self._codecs: dict[str, str] = {}
        """Entity → the codec logged statically on it."""
        self._skipped: dict[str, int] = {}
        """Topic → samples skipped before its first keyframe (a topic is in ``_started`` from that keyframe)."""
        self._started: set[str] = set()

    def encode(
        self, topic: str, time_ns: int, decoded: Decoded | list[MarkerOp] | MsgError
    ) -> Decoded | list[MarkerOp] | MsgError:
        """``decoded`` with a raw image replaced by its video sample(s) (with ``--video``; its topic's encoder
        takes it), in time order per topic."""
        if self.encoder is None or not isinstance(decoded, Decoded) or len(decoded.items) != 1:
            return decoded
        image = decoded.items[0]
        if not isinstance(image, Image):
            return decoded
        encoder = self._encoders.get(topic)
        if encoder is None:
            keyint = 1.0 if self.live else 2.0
            encoder = self._encoders[topic] = VideoEncoder(self.encoder, live=self.live, keyint_s=keyint)
        if not encoder.takes(image):
            return decoded
        try:
            samples = encoder.encode(image, time_ns)
        except Exception as exc:  # PyAV's errors (av.error.FFmpegError): the encoder refuses this frame
            raise MsgError(f"cannot encode as {self.encoder}: {exc}") from None
        return dataclasses.replace(decoded, items=tuple(samples))

    def notes(self, topic: str) -> Iterator[str]:
        """What the topic's encoder has to say (a size change, a refused encoding), each once."""
        encoder = self._encoders.get(topic)
        while encoder is not None and encoder.notes:
            yield encoder.notes.pop(0)

    def ready(self, rec: rr.RecordingStream, topic: str, decoded: Decoded | list[MarkerOp]) -> bool:
        """Whether ``decoded`` is to be logged: anything but a video sample before its stream's first keyframe.
        A stream's codec is logged (statically) before its first sample."""
        if not isinstance(decoded, Decoded) or not decoded.items or not isinstance(decoded.items[0], VideoSample):
            return True
        sample = decoded.items[0]
        if topic not in self._started:
            if not sample.keyframe:
                self._skipped[topic] = self._skipped.get(topic, 0) + 1
                return False
            self._started.add(topic)
        if self._codecs.get(topic) != sample.codec:
            rec.log(topic, rr.VideoStream.from_fields(codec=sample.codec), static=True)
            self._codecs[topic] = sample.codec
        return True

    def finish(self) -> Iterator[tuple[str, str]]:
        """(topic, line) for each stream that started without a keyframe, or never had one."""
        for topic, skipped in self._skipped.items():
            if topic in self._started:
                yield topic, f"the video starts without a keyframe: {skipped} samples skipped up to the first one"
            else:
                yield topic, f"the video has no keyframe: its {skipped} samples cannot be shown"
        for topic, encoder in self._encoders.items():
            held = encoder.close()
            if held:
                encoder.notes.append(f"the encoder held back the last {held} frames")
            yield from ((topic, note) for note in encoder.notes)

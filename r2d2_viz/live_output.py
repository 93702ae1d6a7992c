"""Where a live run (``--ros``) is written: its sinks, ``--save out.rrd`` (a hidden partial renamed when whole) or
``--save out.mcap`` (what was received); on failure nothing half-written."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable

from r2d2_viz.errors import R2d2VizError
from r2d2_viz.ros_out.live_record import LiveBagRecorder
from r2d2_viz.viewer.files.whole import WriterStuckError, not_saved, saved_rrd
from r2d2_viz.viewer.layout.blueprint import generate_blueprint
from r2d2_viz.viewer.layout.plan import ViewPlan
from r2d2_viz.viewer.sinks import Recording, SinkConfig, close_recording, open_recording


class LiveOutput:
    """Where a live run is written: the sinks, ``--save out.rrd`` (renamed when done) or ``out.mcap`` (as received)."""

    def __init__(self, sink: SinkConfig) -> None:
        save = sink.save
        self.bag_path = save if save is not None and save.suffix == ".mcap" else None
        self.rrd = save if self.bag_path is None else None
        self.sink = dataclasses.replace(sink, save=None, headless=not sink.live) if self.bag_path else sink
        self.tmp = self.rrd.with_name(f".{self.rrd.name}.{os.getpid()}.partial") if self.rrd is not None else None
        self.recording: Recording | None = None
        self.bag: LiveBagRecorder | None = None

    def open(self, view: ViewPlan, on_ready: Callable[[str], None] | None) -> Recording:
        self.bag = LiveBagRecorder(self.bag_path) if self.bag_path is not None else None
        blueprint = generate_blueprint(view.spec, layout=view.layout)
        self.recording = open_recording(self.sink, save_to=self.tmp, on_ready=on_ready, blueprint=blueprint)
        return self.recording

    def close(self) -> None:
        with saved_rrd(self.tmp, self.rrd):  # renamed over ``--save`` only when whole; removed otherwise
            if self.recording is not None:
                recording, self.recording = self.recording, None
                close_recording(recording)
        if self.bag is not None:
            self.bag.close()
            self.bag = None

    def abort(self, exc: BaseException | None = None) -> None:
        """Nothing half-written: the partial files removed; a file sink stuck on a full disk (``exc``) says why."""
        try:
            if self.recording is not None and not isinstance(exc, WriterStuckError):  # stuck: a flush would hang
                close_recording(self.recording)
        except (R2d2VizError, WriterStuckError):
            pass  # the error being handled says more
        finally:
            if self.bag is not None:
                self.bag.abort()
            if self.tmp is not None and not isinstance(exc, WriterStuckError):
                self.tmp.unlink(missing_ok=True)
        if isinstance(exc, WriterStuckError) and self.tmp is not None and self.rrd is not None:
            raise not_saved(self.rrd, self.tmp, stuck=True) from None  # the partial removed, the cause named

"""Every topic's health in the recording (``--tf-tree`` with a sink, on a bag): ``/health/<topic>/rate`` (Hz),
``…/bandwidth`` (B/s), for messages with a header ``…/latency`` (s, receive time − header stamp) and, for a ROS 1
topic of one publisher, ``…/drops`` (``header.seq`` numbers missing in the window) as time series
(:mod:`r2d2_viz.sources.system.topic_health`), logged once before the replay, beside the TF graph."""

from __future__ import annotations

import numpy as np
import rerun as rr

from r2d2_viz.sources.base import Clock
from r2d2_viz.sources.plan import BagReplay
from r2d2_viz.sources.system.time_base import RECEIVE
from r2d2_viz.sources.system.topic_health import TopicHealth, messages_base, read_messages, series
from r2d2_viz.viewer import entities
from r2d2_viz.viewer.columns import encoded, send, time_array
from r2d2_viz.viewer.system.tf_graph import WINDOW_NS as TF_WINDOW_NS
from r2d2_viz.viewer.system.tf_graph import TfGraph

ROOT = "/health"


def health_entity(topic: str, series: str) -> str:
    return f"{ROOT}/{topic.strip('/')}/{series}"


def log_health(rec: rr.RecordingStream, series: list[TopicHealth], clock: Clock) -> int:
    """Each topic's series (NaN samples left out); the number of samples logged."""
    logged = 0
    for h in series:
        named = [("rate", h.rate_hz), ("bandwidth", h.bandwidth), ("latency", h.latency_s)]
        for name, values in named if h.drops is None else [*named, ("drops", h.drops)]:
            keep = np.isfinite(values)
            if not keep.any():
                continue
            columns = rr.Scalars.columns(scalars=values[keep])
            send(
                rec,
                health_entity(h.topic, name),
                entities.TIMELINE,
                time_array(h.times_ns[keep], clock),
                encoded(columns),
            )
            logged += int(keep.sum())
    return logged


def system_views(rec: rr.RecordingStream, clock: Clock, replay: BagReplay | None) -> TfGraph:
    """``--tf-tree`` with a sink: the TF graph (fed as transforms are logged) and, replaying a bag, every topic's
    health over the replayed stretch (its last message included), both on the run's time base: with ``--time
    header``, the header clock as the bag's headers give it (:mod:`~r2d2_viz.sources.system.time_base`)."""
    if replay is None:
        return TfGraph(rec, clock=clock)
    start, stop = replay.span[0], replay.segments[-1].stop_ns
    messages = read_messages(replay.bag, start, stop)
    base = messages_base(messages) if replay.time == "header" else RECEIVE
    log_health(rec, [h.retimed(base) for h in series(replay.bag, messages)], clock)
    length = (stop if stop is not None else replay.span[1]) - start
    return TfGraph(rec, clock=clock, time_base=base, horizon_ns=length + TF_WINDOW_NS)

"""The fleet summary: one row per recording of a dataset, from Rerun's catalog (never from the bags).

How each column is worked out (from what :mod:`r2d2_viz.viewer.catalog` reads):

* ``bag``, ``recording_id``: the ``r2d2_viz`` recording property a fleet conversion writes, and the segment id;
* ``duration_s``: the segment table's ``time`` range (last minus first sample or message, any entity);
* ``topics``, ``topic_list``, ``messages_<Type>``: the ``bag_topics`` property (the bag's index at conversion:
  topic → type and message count); messages are summed per type of the topics the app draws — JointState,
  TFMessage and the display types of :data:`r2d2_viz.msgs.registry.DECODERS` — short names (``LaserScan``);
* ``distance_m``: the path length of the robot's base (its URDF root link: the robot's link that is no robot
  link's child) in the fixed frame (the root of the TF tree above it), over the /tf and /tf_static rows: at
  every time any edge of the chain moves (from when all of them are known), the chain composed (each edge's
  latest value), and the lengths of the steps summed; 0 when nothing moves it, empty without a robot;
* ``max_joint_speed``, ``fastest_joint``: the largest |Δq| / Δt between consecutive samples of the joint plots
  (``/joints/limited``, ``/joints/continuous``: rad/s, or m/s for prismatic joints), and its joint (of rows at one
  time the last stands, as in the viewer).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa

from r2d2_viz.errors import UsageError
from r2d2_viz.msgs.registry import DECODERS
from r2d2_viz.viewer.catalog import FleetData

DRAWN_TYPES = (*DECODERS, "sensor_msgs/msg/JointState", "tf2_msgs/msg/TFMessage")
Edge = tuple[str, str, np.ndarray, np.ndarray, np.ndarray]


def summarise(data: FleetData) -> pa.Table:
    """One row per segment, sorted by bag name; columns as the module's docstring says."""
    rows = []
    for segment in data.segments.to_pylist():
        sid = segment["segment"]
        topics = json.loads(segment["topics"]) if segment["topics"] else None
        start, end = segment["start_ns"], segment["end_ns"]
        times, values, names = data.joints.get(sid, (np.zeros(0), np.zeros((0, 0)), []))
        speed, fastest = max_joint_speed(times, values, names)
        distance, base, fixed = base_travel(data.edges.get(sid, []), data.links.get(sid, set()))
        row: dict[str, object] = {
            "bag": segment["bag"],
            "recording_id": sid,
            "duration_s": (end - start) / 1e9 if start is not None and end is not None else None,
            "topics": len(topics) if topics is not None else None,
            "topic_list": " ".join(sorted(topics)) if topics is not None else None,
            "distance_m": distance,
            "base_frame": base,
            "fixed_frame": fixed,
            "max_joint_speed": speed,
            "fastest_joint": fastest,
        }
        for column, count in messages_per_type(topics or {}).items():
            row[column] = count
        rows.append(row)
    columns = sorted({k for r in rows for k in r if k.startswith("messages_")})
    for r in rows:
        for c in columns:
            r.setdefault(c, 0)
    rows.sort(key=lambda r: (str(r["bag"]), str(r["recording_id"])))
    return pa.Table.from_pylist(rows) if rows else pa.table({"bag": pa.array([], pa.string())})


def messages_per_type(topics: dict[str, list[object]]) -> dict[str, int]:
    """``{"messages_LaserScan": 12, …}`` over the topics whose type the app draws."""
    out: dict[str, int] = {}
    for msgtype, count in topics.values():
        if msgtype in DRAWN_TYPES:
            key = "messages_" + str(msgtype).rsplit("/", 1)[-1]
            out[key] = out.get(key, 0) + int(str(count))
    return out


def max_joint_speed(times_ns: np.ndarray, values: np.ndarray, names: list[str]) -> tuple[float | None, str | None]:
    """The largest |Δq| / Δt between consecutive samples, and whose (None: fewer than two samples, no joint)."""
    if len(times_ns) < 2 or not names:  # a recording without a robot, or without joints
        return None, None
    order = np.argsort(times_ns, kind="stable")
    times_ns, values = times_ns[order].astype(np.int64), values[order]
    last = np.r_[times_ns[1:] != times_ns[:-1], True]  # several rows at one time: the last one stands
    times_ns, values = times_ns[last], values[last]
    if len(times_ns) < 2 or not names:
        return None, None
    speeds = np.abs(np.diff(values, axis=0)) / (np.diff(times_ns) / 1e9)[:, None]
    if not np.isfinite(speeds).any():
        return None, None
    flat = int(np.nanargmax(np.where(np.isfinite(speeds), speeds, -1.0)))
    return float(speeds.flat[flat]), names[flat % len(names)]


def base_travel(edges: list[Edge], links: set[str]) -> tuple[float | None, str | None, str | None]:
    """Path length of the robot's base in the fixed frame, the base and that frame (module docstring)."""
    merged: dict[tuple[str, str], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    for parent, child, times, xyz, quat in edges:
        if (parent, child) in merged:
            t0, v0, q0 = merged[(parent, child)]
            times, xyz, quat = np.concatenate([t0, times]), np.vstack([v0, xyz]), np.vstack([q0, quat])
        merged[(parent, child)] = (times, xyz, quat)
    parent_of = {child: parent for parent, child in merged}
    bases = sorted(link for link in links if parent_of.get(link) not in links)
    if not bases:
        return None, None, None
    base = bases[0]
    chain: list[tuple[str, str]] = []
    frame = base
    while frame in parent_of and len(chain) <= len(parent_of):
        chain.append((parent_of[frame], frame))
        frame = parent_of[frame]
    moving = [merged[e] for e in chain if len(merged[e][0])]
    if not moving:
        return 0.0, base, frame
    start = max(int(t.min()) for t, _, _ in moving)
    grid = np.unique(np.concatenate([t for t, _, _ in moving]))
    grid = grid[grid >= start]
    position = np.zeros((len(grid), 3))
    for edge in chain:  # from the base up: p ← R(q) p + t
        t, xyz, quat = merged[edge]
        if len(t):
            order = np.argsort(t, kind="stable")
            k = order[np.searchsorted(t[order], grid, side="right") - 1]
            v, q = xyz[k], quat[k]
        else:
            v, q = np.broadcast_to(xyz[-1], (len(grid), 3)), np.broadcast_to(quat[-1], (len(grid), 4))
        position = _rotate(q, position) + v
    return float(np.linalg.norm(np.diff(position, axis=0), axis=1).sum()), base, frame


def _rotate(q_xyzw: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate each ``v`` by its unit quaternion (normalised here)."""
    q = q_xyzw / np.linalg.norm(q_xyzw, axis=1, keepdims=True)
    u, w = q[:, :3], q[:, 3:4]
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def write_summary(table: pa.Table, out: Path) -> None:
    """``out.csv`` or ``out.parquet``, written beside and renamed into place."""
    if out.suffix not in (".csv", ".parquet"):
        raise UsageError(f"--summary {out}: write a .csv or a .parquet file")
    if not out.parent.is_dir():
        raise UsageError(f"--summary {out}: directory {str(out.parent)!r} does not exist")
    tmp = out.with_name(f".{out.name}.partial")
    try:
        if out.suffix == ".csv":
            import pyarrow.csv as pacsv

            pacsv.write_csv(table, tmp)
        else:
            import pyarrow.parquet as pq

            pq.write_table(table, tmp)
        tmp.replace(out)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise UsageError(f"--summary {out}: cannot write: {exc.strerror}") from None


def format_summary(table: pa.Table) -> str:
    """The table as aligned text, one recording a line (numbers to 3 decimals)."""
    names = [n for n in table.schema.names if n not in ("recording_id", "topic_list")]
    cells = [[_cell(v) for v in row.values()] for row in table.select(names).to_pylist()]
    widths = [max(len(n), *(len(r[i]) for r in cells)) for i, n in enumerate(names)]
    lines = ["  ".join(n.ljust(w) for n, w in zip(names, widths, strict=True))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    return "\n".join(line.rstrip() for line in lines)


def _cell(value: object) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.3f}"
    return str(value)

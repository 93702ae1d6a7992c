#!/usr/bin/env python3
"""Write the MCAP conformance variants (``X.mcap``) from their ``X.json``: a line-by-line port of the suite's own
generator (foxglove/mcap ``tests/conformance/scripts/generate-inputs.ts`` with ``@mcap/core``'s
``McapRecordBuilder`` and ``ChunkBuilder``, commit 95d067356). The upstream repository keeps the ``.mcap`` files in
Git LFS; ``SHA256SUMS`` holds the sha256 and size of each from its LFS pointer, and this script refuses to write a
file whose bytes differ from upstream's. Run from anywhere: ``python tests/data/mcap_conformance/generate.py``.
"""

from __future__ import annotations

import hashlib
import json
import struct
import sys
import zlib
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
MAGIC = b"\x89MCAP0\r\n"
OP = {"Header": 1, "Footer": 2, "Schema": 3, "Channel": 4, "Message": 5, "Chunk": 6, "MessageIndex": 7}
OP |= {"ChunkIndex": 8, "Attachment": 9, "AttachmentIndex": 10, "Statistics": 11, "Metadata": 12}
OP |= {"MetadataIndex": 13, "DataEnd": 15, "SummaryOffset": 14}
PAD = b"\x01\xff\xff"


def _string(s: str) -> bytes:
    b = s.encode()
    return struct.pack("<I", len(b)) + b


def _map(pairs: list[tuple[bytes, bytes]]) -> bytes:
    body = b"".join(k + v for k, v in pairs)
    return struct.pack("<I", len(body)) + body


def _bytes(values: list[str]) -> bytes:
    return bytes(int(v) for v in values)


class Builder:
    """``McapRecordBuilder``: records into one buffer, padded with 3 bytes where ``pad`` and the record allows."""

    def __init__(self, pad: bool = False) -> None:
        self.buf = bytearray()
        self.pad = pad

    def record(self, op: str, body: bytes, paddable: bool = True) -> int:
        if self.pad and paddable:
            body += PAD
        self.buf += bytes([OP[op]]) + struct.pack("<Q", len(body)) + body
        return 9 + len(body)

    def schema(self, r: dict[str, Any]) -> int:
        data = _bytes(r["data"])
        body = struct.pack("<H", int(r["id"])) + _string(r["name"]) + _string(r["encoding"])
        return self.record("Schema", body + struct.pack("<I", len(data)) + data)

    def channel(self, r: dict[str, Any]) -> int:
        meta = _map([(_string(k), _string(v)) for k, v in r["metadata"].items()])
        body = struct.pack("<HH", int(r["id"]), int(r["schema_id"]))
        return self.record("Channel", body + _string(r["topic"]) + _string(r["message_encoding"]) + meta)

    def message(self, r: dict[str, Any]) -> int:
        head = struct.pack(
            "<HIQQ", int(r["channel_id"]), int(r["sequence"]), int(r["log_time"]), int(r["publish_time"])
        )
        return self.record("Message", head + _bytes(r["data"]), paddable=False)


def generate(variant: dict[str, Any]) -> bytes:
    """The file of one variant (its JSON: the records and ``meta.variant.features``)."""
    features = set(variant["meta"]["variant"]["features"])
    types = [r["type"] for r in variant["records"]]
    data_section = variant["records"][: types.index("DataEnd")]  # the summary repeats schemas and channels
    records = [(r["type"], dict(r["fields"])) for r in data_section]
    records = [(t, f) for t, f in records if t in ("Schema", "Channel", "Message", "Attachment", "Metadata")]
    b = Builder(pad="pad" in features)
    b.buf += MAGIC
    b.record("Header", _string("") + _string(""))
    chunk = Builder() if "ch" in features else None
    indices: dict[int, list[tuple[int, int]]] | None = {} if chunk is not None and "mx" in features else None
    chunk_span: tuple[int, int] = (0, 0)
    chunk_messages = 0
    counts = {"message": 0, "channel": 0, "schema": 0, "attachment": 0, "metadata": 0}
    start: int | None = None
    end: int | None = None
    channel_counts: dict[int, int] = {}
    attachment_indexes: list[bytes] = []
    metadata_indexes: list[bytes] = []
    chunk_indexes: list[bytes] = []
    for kind, r in records:
        if kind == "Schema":
            counts["schema"] += 1
            (chunk or b).schema(r)
        elif kind == "Channel":
            counts["channel"] += 1
            if indices is not None:
                indices.setdefault(int(r["id"]), [])
            (chunk or b).channel(r)
        elif kind == "Message":
            counts["message"] += 1
            t = int(r["log_time"])
            channel_counts[int(r["channel_id"])] = channel_counts.get(int(r["channel_id"]), 0) + 1
            if chunk is not None:
                lo, hi = chunk_span
                chunk_span = (t if chunk_messages == 0 or t < lo else lo, t if chunk_messages == 0 or t > hi else hi)
                if indices is not None:
                    indices.setdefault(int(r["channel_id"]), []).append((t, len(chunk.buf)))
                chunk_messages += 1
                chunk.message(r)
            else:
                b.message(r)
            start = t if start is None or t < start else start
            end = t if end is None or t > end else end
        elif kind == "Attachment":
            counts["attachment"] += 1
            offset = len(b.buf)
            data = _bytes(r["data"])
            crc_part = struct.pack("<QQ", int(r["log_time"]), int(r["create_time"])) + _string(r["name"])
            crc_part += _string(r["media_type"]) + struct.pack("<Q", len(data)) + data
            length = b.record("Attachment", crc_part + struct.pack("<I", zlib.crc32(crc_part)))
            if "ax" in features:
                fields = struct.pack("<QQQQQ", offset, length, int(r["log_time"]), int(r["create_time"]), len(data))
                attachment_indexes.append(fields + _string(r["name"]) + _string(r["media_type"]))
        elif kind == "Metadata":
            counts["metadata"] += 1
            offset = len(b.buf)
            meta = _map([(_string(k), _string(v)) for k, v in r["metadata"].items()])
            length = b.record("Metadata", _string(r["name"]) + meta)
            if "mdx" in features:
                metadata_indexes.append(struct.pack("<QQ", offset, length) + _string(r["name"]))
    if chunk is not None:
        chunk_start = len(b.buf)
        records_bytes = bytes(chunk.buf)
        head = struct.pack("<QQQI", *chunk_span, len(records_bytes), zlib.crc32(records_bytes))
        body = head + _string("") + struct.pack("<Q", len(records_bytes)) + records_bytes
        chunk_length = b.record("Chunk", body, paddable=False)
        offsets: list[tuple[int, int]] = []
        index_length = 0
        for channel_id, rows in (indices or {}).items():
            offsets.append((channel_id, len(b.buf)))
            body = struct.pack("<HI", channel_id, 16 * len(rows)) + b"".join(struct.pack("<QQ", *x) for x in rows)
            index_length += b.record("MessageIndex", body)
        if "chx" in features:
            body = struct.pack("<QQQQ", *chunk_span, chunk_start, chunk_length)
            body += struct.pack("<I", 10 * len(offsets)) + b"".join(struct.pack("<HQ", *o) for o in offsets)
            n = len(records_bytes)
            chunk_indexes.append(body + struct.pack("<Q", index_length) + _string("") + struct.pack("<QQ", n, n))
    b.record("DataEnd", struct.pack("<I", zlib.crc32(b.buf)), paddable=False)
    summary_start = len(b.buf)
    groups: list[tuple[str, int, int]] = []

    def group(op: str, bodies: list[bytes]) -> None:
        at = len(b.buf)
        for body in bodies:
            b.record(op, body)
        groups.append((op, at, len(b.buf) - at))

    at = len(b.buf)
    if "rsh" in features:
        for kind, r in records:
            if kind == "Schema":
                b.schema(r)
    groups.append(("Schema", at, len(b.buf) - at))
    at = len(b.buf)
    if "rch" in features:
        for kind, r in records:
            if kind == "Channel":
                b.channel(r)
    groups.append(("Channel", at, len(b.buf) - at))
    stats: list[bytes] = []
    if "st" in features:
        c = counts
        body = struct.pack(
            "<QHIIII", c["message"], c["schema"], c["channel"], c["attachment"], c["metadata"], 1 if chunk else 0
        )
        body += struct.pack("<QQ", start or 0, end or 0)
        stats.append(body + _map([(struct.pack("<H", k), struct.pack("<Q", v)) for k, v in channel_counts.items()]))
    group("Statistics", stats)
    group("MetadataIndex", metadata_indexes)
    group("AttachmentIndex", attachment_indexes)
    group("ChunkIndex", chunk_indexes)
    has_summary = len(b.buf) != summary_start
    summary_offset_start = 0
    if "sum" in features:
        summary_offset_start = len(b.buf)
        for op, at, length in groups:
            if length:
                b.record("SummaryOffset", struct.pack("<BQQ", OP[op], at, length))
    footer = bytes([OP["Footer"]]) + struct.pack("<QQQ", 20, summary_start if has_summary else 0, summary_offset_start)
    crc = zlib.crc32(footer, zlib.crc32(b.buf[summary_start:]))
    b.buf += footer + struct.pack("<I", crc) + MAGIC
    return bytes(b.buf)


def upstream_sums(root: Path = HERE) -> dict[str, tuple[str, int]]:
    """``relative path → (sha256, size)`` of upstream's files (``SHA256SUMS``)."""
    sums = {}
    for line in (root / "SHA256SUMS").read_text().splitlines():
        digest, size, name = line.split()
        sums[name] = (digest, int(size))
    return sums


def main() -> int:
    sums = upstream_sums()
    wrong = 0
    for name, (digest, size) in sorted(sums.items()):
        path = HERE / name
        data = generate(json.loads(path.with_suffix(".json").read_text()))
        if hashlib.sha256(data).hexdigest() != digest or len(data) != size:
            print(f"{name}: not upstream's bytes", file=sys.stderr)
            wrong += 1
            continue
        path.write_bytes(data)
    print(f"{len(sums) - wrong} of {len(sums)} variants written, byte-identical to upstream's")
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())

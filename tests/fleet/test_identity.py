"""A bag's identity for the fleet (issue 25): names, recording ids (the same bag → the same id; other names,
sizes or times → other ids), up to date or not — on bags written by rosbags."""

from __future__ import annotations

import os
import uuid
from pathlib import Path

import pytest
from bagmaker import storage_file
from fleetbags import still_bag

from r2d2_viz.errors import UsageError
from r2d2_viz.fleet.identity import identify, is_up_to_date, output_path


def test_names_sizes_and_the_documented_id(tmp_path: Path) -> None:
    bag = still_bag(tmp_path / "run_07")
    found = identify(bag)
    files = list(bag.iterdir())
    assert found.name == "run_07" and found.size == sum(p.stat().st_size for p in files)
    assert found.mtime_ns == max(p.stat().st_mtime_ns for p in files)
    namespace = uuid.UUID("5d6c1e1a-25f1-4c0e-9a55-2d2f1ee7a25e")
    assert found.recording_id == str(uuid.uuid5(namespace, f"run_07\0{found.size}\0{found.mtime_ns}"))
    assert identify(storage_file(bag)).name == storage_file(bag).stem
    assert output_path(tmp_path, found) == tmp_path / "run_07.rrd"


def test_the_same_bag_the_same_id_others_other_ids(tmp_path: Path) -> None:
    a = still_bag(tmp_path / "a")
    assert identify(a).recording_id == identify(a).recording_id
    (tmp_path / "copy").mkdir()
    b = tmp_path / "copy" / "b"
    os.rename(still_bag(tmp_path / "copy" / "tmp"), b)
    ids = {identify(a).recording_id, identify(b).recording_id}
    later = identify(a).mtime_ns + 10**9
    os.utime(storage_file(a), ns=(later, later))  # touched: another bag as far as the id goes
    ids.add(identify(a).recording_id)
    assert len(ids) == 3


def test_missing_and_non_bags_are_one_line(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="no such bag"):
        identify(tmp_path / "nope")
    (tmp_path / "empty").mkdir()
    with pytest.raises(UsageError, match=r"no \.mcap or \.db3 file is not a bag"):
        identify(tmp_path / "empty")


def test_up_to_date_needs_a_newer_output_the_id_and_this_version(tmp_path: Path) -> None:
    bag = identify(still_bag(tmp_path / "a"))
    out = tmp_path / "a.rrd"
    marker = (bag.recording_id, bag.marker("1.0"))
    assert not is_up_to_date(out, bag, marker, "1.0")  # no output yet
    out.write_bytes(b"")
    os.utime(out, ns=(bag.mtime_ns + 1, bag.mtime_ns + 1))
    assert is_up_to_date(out, bag, marker, "1.0")
    assert not is_up_to_date(out, bag, marker, "1.1")  # another version of the app
    assert not is_up_to_date(out, bag, (str(uuid.uuid4()), bag.marker("1.0")), "1.0")
    assert not is_up_to_date(out, bag, None, "1.0")  # unreadable output
    os.utime(out, ns=(bag.mtime_ns - 1, bag.mtime_ns - 1))
    assert not is_up_to_date(out, bag, marker, "1.0")  # older than the bag

"""Plain items (logs, diagnostic statuses, numbers, fixes) on entities of their own: what a topic's book remembers.

Expected values by hand (a status's states in order; two status names that escape to one path get a lane each)."""

from __future__ import annotations

from r2d2_viz.viewer.blocks.plain_log import PlainBook, log_plain, state_of


def test_a_field_keeps_the_kind_it_was_first_logged_as() -> None:
    """Rerun fixes a component's type at its first row: a key first seen as text stays text."""
    import rerun as rr

    from r2d2_viz.msgs.shapes import Status, Statuses
    from r2d2_viz.msgs.telemetry import KINDS

    rec = rr.RecordingStream("test", recording_id="t")
    book = PlainBook()
    log_plain(rec, "/d", Statuses((Status(("a",), "OK", "", "", (("kind test key", "idle"),)),)), book)
    log_plain(rec, "/d", Statuses((Status(("a",), "WARN", "m", "", (("kind test key", "3.5"),)),)), book)
    assert KINDS["kind test key"] is False
    assert book.states["/d/a"] == ["OK", "WARN: m"]
    assert state_of(Status(("a",), "ERROR", "", "", ())) == "ERROR"


def test_distinct_status_names_that_make_the_same_path_get_a_lane_each() -> None:
    """`motor: left` and `motor left` both make `motor_left`: two names, two lanes (by hand)."""
    import rerun as rr

    from r2d2_viz.msgs.shapes import Status, Statuses

    rec = rr.RecordingStream("test", recording_id="lanes")
    book = PlainBook()
    for name in ("motor: left", "motor left", "motor: left"):
        log_plain(rec, "/d", Statuses((Status(("motor_left",), "OK", "", "", (), name),)), book)
    assert book.lanes == {"/d/motor_left": "motor: left", "/d/motor_left_": "motor left"}

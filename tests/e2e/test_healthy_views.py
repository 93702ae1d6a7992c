"""No view of the real viewer reports an error (Rerun's red badge) on any real bag of the suite, nor on bags
written here by rosbags for what real bags hold: camera images without a CameraInfo, markers deleted and expired,
markers in a frame the bag never connects to the others.

Asked through the viewer's own API (``rerun.experimental.ViewerClient``: a windowless native viewer, one for the
session, ``get_state().views[i].reports``) at nine times spread over each recording, the last included, from the
time every recorded transform has arrived once (read from the recording's /tf rows): before it, a robot or a
frame not placed yet is reported, and RViz says the same ("No transform from [base_link] to [odom]") until its
first transform comes. The one error allowed after it is RViz's own for a frame no transform ever reaches ("No
transform from [person] to [laser]"): the viewer reports it too, and the run says so once on stderr.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from bagmaker import BagSpec, tf_message, write_bag
from conftest import REPO, cli
from msgs_build import T, cdr, color, header, marker_msg, pose, quat, vec
from rrd import read_recording, tf_by_child

from . import viewers

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

S = 1_000_000_000
T0 = 1_700_000_000 * S
REAL = ("webots_epuck", "lightware_sf45b", "cdrr_rehab")
PLACES = (REPO / "tests" / "data" / "bags" / "real", REPO.parent / "shared" / "bags" / "real")


def real_bag(name: str) -> Path:
    for place in PLACES:
        if (place / name / "metadata.yaml").is_file():
            return place / name
    pytest.skip(f"bag {name} is not in this checkout (looked in {', '.join(str(p) for p in PLACES)})")


def record(bag: Path, out: Path, *args: str) -> tuple[Path, str]:
    """``r2d2-viz --bag BAG --save OUT``: the recording and what the run said on stderr."""
    run = cli("--bag", str(bag), "--save", str(out), *args)
    assert run.returncode == 0, run.stderr
    return out, run.stderr


def errors(reports: list[viewers.Report]) -> list[str]:
    """Each distinct error, once."""
    return sorted({f"{r.view}: {r.summary}" for r in reports if r.severity == "error"})


def settled(rrd: Path) -> int | None:
    """The time every moving transform of the recording has been received once (None: it has none)."""
    children = tf_by_child(read_recording(rrd))
    return max((rows.times[0] for rows in children.values() if rows.times), default=None)


def reports(client, rrd: Path) -> list[str]:
    return errors(viewers.view_reports(client, rrd, since_ns=settled(rrd)))


@pytest.mark.parametrize("name", REAL)
def test_no_view_reports_an_error_on_a_real_bag(name: str, headless_client, tmp_path: Path) -> None:
    rrd, _ = record(real_bag(name), tmp_path / f"{name}.rrd")
    assert reports(headless_client, rrd) == []


# --------------------------------------------------------------------------------------------------
# Bags written here


def _image(frame: str, t_ns: int) -> bytes:
    pixels = np.zeros((4, 6, 3), dtype=np.uint8)
    pixels[..., 0] = 200
    return cdr(
        T("sensor_msgs/msg/Image")(
            header=header(frame, *divmod(t_ns, S)), height=4, width=6, encoding="rgb8", is_bigendian=0, step=18,
            data=pixels.reshape(-1),
        )
    )  # fmt: skip


def _camera_info(frame: str, t_ns: int) -> bytes:
    return cdr(
        T("sensor_msgs/msg/CameraInfo")(
            header=header(frame, *divmod(t_ns, S)), height=4, width=6, distortion_model="plumb_bob", d=np.zeros(5),
            k=np.array([5.0, 0, 3, 0, 5.0, 2, 0, 0, 1]), r=np.eye(3).reshape(-1), p=np.zeros(12), binning_x=0,
            binning_y=0,
            roi=T("sensor_msgs/msg/RegionOfInterest")(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
        )
    )  # fmt: skip


def camera_bag(path: Path, *, camera_info: bool) -> Path:
    """A robot's camera (``odom`` → ``base_link`` → ``camera``) publishing images for 2 s, with or without its
    CameraInfo beside them (``/cam/camera_info``)."""
    types = {"/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage"}
    types["/cam/image_raw"] = "sensor_msgs/msg/Image"
    if camera_info:
        types["/cam/camera_info"] = "sensor_msgs/msg/CameraInfo"
    spec = BagSpec(types=types)
    spec.add("/tf_static", T0, tf_message([(T0, "base_link", "camera", (0.1, 0.0, 0.3), (0, 0, 0, 1))]))
    for k in range(21):
        t = T0 + k * S // 10
        spec.add("/tf", t, tf_message([(t, "odom", "base_link", (0.05 * k, 0.0, 0.0), (0, 0, 0, 1))]))
        if k % 2 == 0:  # (an image before its camera's first CameraInfo has no pinhole yet: RViz's Camera
            # display waits for one; the viewer would report that instant)
            if camera_info:
                spec.add("/cam/camera_info", t + 1_000_000, _camera_info("camera", t))
            spec.add("/cam/image_raw", t + 2_000_000, _image("camera", t))
    spec.messages.sort(key=lambda m: m[1])
    return write_bag(path, spec, storage="mcap")


def _person(action: int, key: int, t_ns: int, frame: str, *, lifetime_s: int = 0) -> object:
    return marker_msg(
        3,  # CYLINDER
        header=header(frame, *divmod(t_ns, S)),
        ns="person",
        id=key,
        action=action,
        pose=pose(1.0 + key, 0.5, 0.9, quat(0, 0, 0, 1)),
        scale=vec(0.4, 0.4, 1.8),
        color=color(0.2, 0.4, 1.0),
        lifetime=T("builtin_interfaces/msg/Duration")(sec=lifetime_s, nanosec=0),
    )


def people_bag(path: Path, *, person_frame: str = "laser") -> Path:
    """A laser on a robot (``odom`` → ``base_link`` → ``laser``) and people markers (/sim_markers) as a people
    tracker publishes them: person 1 appears at 0.5 s and is deleted at 1.2 s, person 2 appears at 0.8 s with a
    0.5 s lifetime (expires at 1.3 s), person 3 appears at 1.5 s; all in ``person_frame``."""
    types = {"/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage"}
    types["/sim_markers"] = "visualization_msgs/msg/MarkerArray"
    spec = BagSpec(types=types)
    spec.add("/tf_static", T0, tf_message([(T0, "base_link", "laser", (0.0, 0.0, 0.2), (0, 0, 0, 1))]))
    for k in range(21):
        t = T0 + k * S // 10
        spec.add("/tf", t, tf_message([(t, "odom", "base_link", (0.0, 0.0, 0.0), (0, 0, 0, 1))]))
    array = T("visualization_msgs/msg/MarkerArray")
    for t_ns, markers in (
        (T0 + 5 * S // 10, [_person(0, 1, T0 + 5 * S // 10, person_frame)]),
        (T0 + 8 * S // 10, [_person(0, 2, T0 + 8 * S // 10, person_frame, lifetime_s=0)]),
        (T0 + 12 * S // 10, [_person(2, 1, T0 + 12 * S // 10, person_frame)]),
        (T0 + 15 * S // 10, [_person(0, 3, T0 + 15 * S // 10, person_frame)]),
    ):
        spec.add("/sim_markers", t_ns, cdr(array(markers=markers)))
    spec.messages.sort(key=lambda m: m[1])
    return write_bag(path, spec, storage="mcap")


@pytest.mark.parametrize("camera_info", [False, True], ids=["without_camera_info", "with_camera_info"])
def test_camera_images_leave_the_3d_view_healthy(camera_info: bool, headless_client, tmp_path: Path) -> None:
    rrd, _ = record(camera_bag(tmp_path / "bag", camera_info=camera_info), tmp_path / "cam.rrd")
    assert reports(headless_client, rrd) == []


def test_deleted_and_expired_markers_leave_the_3d_view_healthy(headless_client, tmp_path: Path) -> None:
    rrd, _ = record(people_bag(tmp_path / "bag"), tmp_path / "people.rrd")
    assert reports(headless_client, rrd) == []


def test_a_frame_the_bag_never_connects_is_said_once_like_rviz(headless_client, tmp_path: Path) -> None:
    rrd, stderr = record(people_bag(tmp_path / "bag", person_frame="person"), tmp_path / "people.rrd")
    # RViz: "No transform from [person] to [odom]"; the viewer the same, while people are shown; nothing else
    view = '3D: odom (Grid · TF · RobotModel): No transform path from "person" to the view\'s target frame ("odom").'
    assert reports(headless_client, rrd) == [view]
    lines = [line for line in stderr.splitlines() if "No transform from" in line]
    assert lines == ["warning: /sim_markers: No transform from [person] to [odom]: nothing joins them in the bag's "
                     "transforms; not shown (RViz says the same)"]  # fmt: skip


def test_the_log_diagnostics_map_and_plots_leave_every_view_healthy(headless_client, tmp_path: Path) -> None:
    """The robot's log, its diagnostics, an Imu (axes in its frame, plots), a fix, a battery and std_msgs topics
    (tests/telemetrybags.py, and ROS 1's real example bag with its /rosout): no view reports an error."""
    from telemetrybags import write_telemetry_bag

    rrd, _ = record(write_telemetry_bag(tmp_path / "tele"), tmp_path / "tele.rrd")
    assert reports(headless_client, rrd) == []
    ros1, _ = record(REPO / "tests" / "data" / "bags" / "ros1" / "example-lz4.bag", tmp_path / "ros1.rrd")
    assert reports(headless_client, ros1) == []

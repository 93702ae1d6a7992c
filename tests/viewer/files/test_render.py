"""The rerun-facing half of ``--render`` without a viewer: which view is drawn, the blueprint that maximises it,
the window that leaves it the asked size and a screenshot's pixels. (The viewer itself: tests/e2e/test_render_e2e.py.)
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from r2d2_viz.viewer.files.render import ChosenView, RenderError, choose_view, maximised, png_pixels, window_for

# as the viewer lists the app's default layout (ViewerClient.get_state().views, seen on the R2D2's recording)
VIEWS = [
    ("a", "Joint states", "TimeSeries"),
    ("b", "3D: odom (Grid · TF · RobotModel)", "3D"),
    ("c", "Warnings", "TextLog"),
    ("d", "Continuous joints", "TimeSeries"),
]


def test_the_3d_view_by_default_else_the_first() -> None:
    assert choose_view(VIEWS, None) == ChosenView("b", "3D: odom (Grid · TF · RobotModel)", "3D")
    assert choose_view(VIEWS[:1], None).view_id == "a"


def test_a_view_by_its_name_or_a_part_of_it_in_any_case() -> None:
    assert choose_view(VIEWS, "Warnings").view_id == "c"
    assert choose_view(VIEWS, "continuous").view_id == "d"
    assert choose_view([*VIEWS, ("e", "Joint states /r1", "TimeSeries")], "Joint states").view_id == "a"  # exact


def test_an_unknown_or_ambiguous_view_is_one_line_naming_the_views() -> None:
    with pytest.raises(RenderError, match=r"--view 'camera' is not a view of the layout; the views: 'Joint st"):
        choose_view(VIEWS, "camera")
    with pytest.raises(RenderError, match="names several views"):
        choose_view(VIEWS, "joint")
    with pytest.raises(RenderError, match="no view"):
        choose_view([], None)
    with pytest.raises(RenderError) as caught:
        choose_view(VIEWS, "x\x1b[2Jy")
    assert "\x1b" not in str(caught.value) and "\n" not in str(caught.value)


def test_the_view_is_maximised_with_the_panels_hidden_and_the_time_paused() -> None:
    # the shape ViewerClient.get_blueprint() reads (rerun 0.41), cut down to the keys that change
    blueprint = {
        "/viewport": {"ViewportBlueprint": {"auto_views": False, "root_container": "r"}},
        "/blueprint_panel": {"PanelBlueprint": {"state": "Expanded"}},
        "/time_panel": {"TimePanelBlueprint": {"play_state": "Playing", "state": "Collapsed", "timeline": "time"}},
        "/view/b": {"ViewBlueprint": {"class_identifier": "3D"}},
    }
    out = maximised(blueprint, "b")
    assert out["/viewport"] == {"ViewportBlueprint": {"auto_views": False, "root_container": "r", "maximized": "b"}}
    assert out["/blueprint_panel"] == out["/selection_panel"] == {"PanelBlueprint": {"state": "Hidden"}}
    assert out["/time_panel"] == {"TimePanelBlueprint": {"play_state": "Paused", "state": "Hidden", "timeline": "time"}}
    assert out["/view/b"] == blueprint["/view/b"]
    assert blueprint["/viewport"]["ViewportBlueprint"] == {"auto_views": False, "root_container": "r"}  # not changed


def test_the_window_grows_by_the_chrome_around_the_view() -> None:
    # seen: a 640x360 window left the maximised view 633x289 (rerun 0.41 headless: 7 px of border, 71 of bars)
    assert window_for((640, 360), (633, 289), (640, 360)) == (647, 431)
    assert window_for((1280, 720), (1280, 720), (1280, 720)) == (1280, 720)


def test_a_screenshot_png_becomes_rgb_pixels() -> None:
    rgba = np.zeros((3, 4, 4), np.uint8)
    rgba[..., 0], rgba[1, 2] = 200, (1, 2, 3, 255)
    buffer = io.BytesIO()
    Image.fromarray(rgba, "RGBA").save(buffer, "PNG")
    pixels = png_pixels(buffer.getvalue())
    assert pixels.shape == (3, 4, 3) and pixels.dtype == np.uint8
    assert pixels[1, 2].tolist() == [1, 2, 3] and pixels[0, 0].tolist() == [200, 0, 0]

"""Joint plots: limited and continuous joints apart, limit lines, out-of-limit samples found once."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
from rrd import read_recording

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.viewer.plots import JointPlots

URDF = """<robot name="r"><link name="a"/><link name="b"/><link name="c"/><link name="d"/>
<joint name="lift" type="prismatic"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
<limit lower="0" upper="0.5" effort="1" velocity="1"/></joint>
<joint name="spin" type="continuous"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/></joint>
<joint name="bend" type="revolute"><parent link="c"/><child link="d"/><axis xyz="0 1 0"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""


def test_series_limits_and_excursions(tmp_path: Path) -> None:
    path = tmp_path / "r.urdf"
    path.write_text(URDF)
    tree = compile_tree(load_urdf(path))
    plots = JointPlots(tree, timeline="time", clock="duration")
    by_entity = {entity: [tree.moving[m] for m in ms] for entity, ms in plots.series}
    assert by_entity == {"/joints/limited": ["lift", "bend"], "/joints/continuous": ["spin"]}
    m = {name: i for i, name in enumerate(tree.moving)}
    values = np.zeros((6, 3))
    values[3, m["lift"]] = 0.6  # sample 3: above lift's 0.5
    values[4:, m["bend"]] = -1.5  # samples 4, 5: below bend's −1
    values[:, m["spin"]] = 100.0  # continuous: no limits
    assert plots.outside(values) == {m["lift"]: 3, m["bend"]: 4}
    message = plots.out_of_limits_message(m["lift"], 0.6, 0.1)
    assert "'lift' left its URDF limits [0, 0.5] at t=0.100 s (value 0.6)" in message
    assert plots.outside(values) == {m["bend"]: 4}  # lift is reported once
    out = tmp_path / "p.rrd"
    rec = rr.RecordingStream("test")
    rec.save(out)
    plots.log_styles(rec)
    plots.log_limits(rec, 1_000_000_000)
    rec.flush()
    rec.disconnect()
    limits = read_recording(out)["/joints/limited/limits"]
    assert limits.static["SeriesLines:names"][-1] == [
        "lift lower limit",
        "lift upper limit",
        "bend lower limit",
        "bend upper limit",
    ]
    assert limits.times == [1_000_000_000] and limits.temporal["Scalars:scalars"][0] == [0.0, 0.5, -1.0, 1.0]

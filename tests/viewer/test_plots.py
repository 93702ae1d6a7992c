"""Joint plots: limited and continuous joints apart, limit lines, out-of-limit samples found once."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from rrd import read_recording

from r2d2_viz.kinematics.tree import compile_tree
from r2d2_viz.robot.model import load_urdf
from r2d2_viz.viewer.columns import encoded
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


@pytest.mark.parametrize("urdf", ["mixed", "all limited"])
def test_plot_columns_are_what_rerun_builds(tmp_path: Path, urdf: str) -> None:
    """The plot columns are built from buffers (issue 38): the same descriptor and rows as ``rr.Scalars.columns``
    partitioned by sample (Rerun's own builder), NaN included; every joint in order takes the path without a
    gather."""
    path = tmp_path / "r.urdf"
    limited = '<joint name="spin" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/>'
    limited += '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
    spin = '<joint name="spin" type="continuous"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/></joint>'
    assert spin in URDF
    path.write_text(URDF if urdf == "mixed" else URDF.replace(spin, limited))
    tree = compile_tree(load_urdf(path))
    plots = JointPlots(tree, timeline="time", clock="duration")
    assert len(plots.series) == (2 if urdf == "mixed" else 1)
    values = np.random.default_rng(1).uniform(-2, 2, (17, 3))
    values[4, 1] = np.nan
    got = plots.encode(values)
    assert [entity for entity, _ in got] == [entity for entity, _ in plots.series]
    for (entity, columns), (_, ms) in zip(got, plots.series, strict=True):
        expected = encoded(rr.Scalars.columns(scalars=values[:, ms].reshape(-1)).partition(np.full(17, len(ms))))
        assert len(columns) == len(expected) == 1
        assert columns[0][0] == expected[0][0]
        assert columns[0][1].type == expected[0][1].type
        assert repr(columns[0][1].to_pylist()) == repr(expected[0][1].to_pylist()), entity  # NaN == NaN as text

"""Synthetic URDFs: random trees and long chains, for the tests and the benchmarks.

``random_urdf`` uses every joint type (fixed, revolute, continuous, prismatic, mimic, floating,
planar) with arbitrary origins and axes, so the kinematics can be cross-checked on more than the R2D2.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import numpy as np

from r2d2_viz.robot.urdf_check import JOINT_TYPES as ALL_JOINT_TYPES


def random_urdf(
    n_links: int,
    *,
    seed: int = 0,
    chain: bool = False,
    joint_types: tuple[str, ...] = ALL_JOINT_TYPES,
    mimic_fraction: float = 0.15,
    visuals: bool = True,
    name: str = "random_robot",
) -> str:
    """A URDF with ``n_links`` links. Link ``i > 0`` hangs from a random earlier link (or from
    ``i - 1`` when ``chain``) by a joint of a random type from ``joint_types``; a fraction of the
    movable joints mimic an earlier actuated joint."""
    rng = np.random.default_rng(seed)
    lines = [f"<robot name={quoteattr(name)}>"]

    def link(i: int) -> None:
        lines.append(f'<link name="link_{i}">')
        if visuals:
            size = " ".join(f"{v:.3f}" for v in rng.uniform(0.02, 0.1, 3))
            rgba = " ".join(f"{v:.3f}" for v in (*rng.uniform(0, 1, 3), 1.0))
            lines.append(
                f'<visual><origin xyz="0 0 0.05"/><geometry><box size="{size}"/></geometry>'
                f'<material name="m{i}"><color rgba="{rgba}"/></material></visual>'
            )
        lines.append("</link>")

    link(0)
    actuated: list[str] = []
    for i in range(1, n_links):
        link(i)
        parent = i - 1 if chain else int(rng.integers(0, i))
        kind = str(rng.choice(joint_types))
        xyz = " ".join(repr(float(v)) for v in rng.uniform(-0.5, 0.5, 3))
        rpy = " ".join(repr(float(v)) for v in rng.uniform(-np.pi, np.pi, 3))
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        body = [
            f'<joint name="joint_{i}" type="{kind}">',
            f'<parent link="link_{parent}"/><child link="link_{i}"/>',
            f'<origin xyz="{xyz}" rpy="{rpy}"/>',
            f'<axis xyz="{" ".join(repr(float(v)) for v in axis)}"/>',
        ]
        if kind in ("revolute", "prismatic"):
            body.append('<limit lower="-1.0" upper="1.0" effort="10" velocity="1"/>')
        if kind in ("revolute", "continuous", "prismatic"):
            if actuated and rng.uniform() < mimic_fraction:
                master = str(rng.choice(actuated))
                mult, offset = rng.uniform(-2, 2), rng.uniform(-0.5, 0.5)
                body.append(f'<mimic joint="{master}" multiplier="{mult!r}" offset="{offset!r}"/>')
            else:
                actuated.append(f"joint_{i}")
        body.append("</joint>")
        lines.extend(body)
    lines.append("</robot>")
    return "\n".join(lines)

"""A link's ``<inertial>``, and what RViz's RobotModel "Mass Properties" draw of it (pure numpy).

* **Mass**: a sphere at the centre of mass "sized as if it were a ball of lead with the same mass as the link"
  (RViz, ``RobotLink::createMass``: density 11,340 kg/m³, ``m = 4/3 π r³ ρ``).
* **Inertia**: the box of equal mass and inertia (RViz, ``RobotLink::createInertia``, through gz-math's
  ``MassMatrix3::EquivalentBox``): its axes are the principal axes of the inertia tensor (its eigenvectors), its
  sides ``x = √(6 (I₂ + I₃ − I₁) / m)`` and the like from the principal moments ``I₁, I₂, I₃`` (a uniform box of
  sides a, b, c has ``I₁ = m (b² + c²) / 12``). gz-math refuses (and RViz shows nothing for) a tensor that is not
  positive definite or whose principal moments break the triangle inequality ``I₁ + I₂ ≥ I₃``: no box is real.

The tensor is written in the frame of ``<inertial><origin>``, rotation included; the box is placed by
``T_link_inertial · R_inertial_principal``. (RViz 2 places it by the origin's position and the principal axes
only, ignoring the origin's rpy; a URDF whose inertial origin is rotated gets the correct box here.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from lxml import etree

from r2d2_viz.arrays import F64

LEAD_DENSITY = 11340.0
"""kg/m³, RViz's ``density_of_lead``."""
_TOLERANCE = 10.0 * float(np.finfo(np.float64).eps)
"""gz-math's ``Epsilon``: 10 machine epsilons (``GZ_MASSMATRIX3_DEFAULT_TOLERANCE``) times the largest moment."""


@dataclass(frozen=True, eq=False)
class Inertial:
    """One ``<inertial>``: mass (kg), the inertia tensor (kg·m², symmetric, in the inertial frame) and
    ``T_link_inertial`` (its ``<origin>``: the centre of mass and the tensor's axes, in the link's frame)."""

    mass: float
    inertia: F64
    T_link_inertial: F64

    @property
    def zero(self) -> bool:
        """No mass and no inertia: a placeholder (frames, sensors), nothing to draw and nothing wrong."""
        return self.mass == 0.0 and not np.any(self.inertia)


@dataclass(frozen=True, eq=False)
class InertiaBox:
    """The box of equal inertia: full side lengths along its own x, y, z, and ``T_link_box`` placing it."""

    size: F64
    T_link_box: F64


def read_inertial(element: etree._Element | None, T_link_inertial: F64) -> Inertial | None:
    """An ``<inertial>`` element (numbers already checked by :func:`r2d2_viz.robot.urdf_check.check_robot`), with
    its origin as given; a missing ``<mass>`` or moment reads as 0 (as urdfdom's defaults)."""
    if element is None:
        return None
    mass_el, tensor_el = element.find("mass"), element.find("inertia")

    def number(el: etree._Element | None, name: str) -> float:
        text = el.get(name) if el is not None else None
        return float(text) if text is not None else 0.0

    ixx, ixy, ixz, iyy, iyz, izz = (number(tensor_el, a) for a in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"))
    tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=np.float64)
    tensor.flags.writeable = False
    return Inertial(number(mass_el, "value"), tensor, T_link_inertial)


def lead_sphere_radius(mass: float) -> float:
    """The radius of a ball of lead of ``mass`` kg (RViz's mass sphere: ``diameter = 2 ∛(¾ m / (π ρ))``)."""
    return math.cbrt(0.75 * max(mass, 0.0) / (math.pi * LEAD_DENSITY))


def principal_axes(inertia: F64) -> tuple[F64, F64]:
    """Principal moments (ascending) and ``R_inertial_principal`` (eigenvectors as columns, a proper rotation)."""
    moments, axes = np.linalg.eigh(np.asarray(inertia, dtype=np.float64))
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return moments, axes


def inertia_problem(inertial: Inertial) -> str | None:
    """Why no box of equal inertia exists (gz-math's checks, RViz's refusal), or None when it does."""
    if inertial.zero:
        return None
    moments, _ = principal_axes(inertial.inertia)
    shown = ", ".join(f"{m:.6g}" for m in moments)
    if not inertial.mass > 0:
        return f"mass {inertial.mass:g} kg is not positive"
    epsilon = _TOLERANCE * float(np.max(np.abs(moments)))
    if not np.all(moments > epsilon):
        return f"inertia is not positive definite (principal moments {shown} kg·m²)"
    low, mid, high = (float(m) for m in moments)
    if low + mid + epsilon < high:
        return f"principal moments {shown} kg·m² violate the triangle inequality ({low:.6g} + {mid:.6g} < {high:.6g})"
    return None


class _Link(Protocol):
    @property
    def name(self) -> str: ...
    @property
    def inertial(self) -> Inertial | None: ...


class _Robot(Protocol):
    """A :class:`r2d2_viz.robot.model.Robot` (which imports this module)."""

    @property
    def source(self) -> str: ...
    @property
    def links(self) -> Sequence[_Link]: ...


def inertia_problems(robot: _Robot) -> list[str]:
    """One line per impossible ``<inertial>``, named as the checker names elements:
    ``arm.urdf: link 'forearm': <inertial>: inertia is not positive definite (…)``."""
    problems = ((link.name, inertia_problem(link.inertial)) for link in robot.links if link.inertial is not None)
    return [f"{robot.source}: link '{name}': <inertial>: {problem}" for name, problem in problems if problem]


def equivalent_box(inertial: Inertial) -> InertiaBox | None:
    """The uniform box of the same mass and inertia, or None when :func:`inertia_problem` says there is none."""
    if inertial.zero or inertia_problem(inertial) is not None:
        return None
    moments, axes = principal_axes(inertial.inertia)
    i1, i2, i3 = moments
    squared = 6.0 / inertial.mass * np.array([i2 + i3 - i1, i3 + i1 - i2, i1 + i2 - i3])
    size = np.sqrt(np.maximum(squared, 0.0))  # within gz-math's tolerance of the triangle: a flat box
    T_inertial_box = np.eye(4)
    T_inertial_box[:3, :3] = axes
    return InertiaBox(size, np.asarray(inertial.T_link_inertial) @ T_inertial_box)

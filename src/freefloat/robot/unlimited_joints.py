"""A warning for a URDF that gives joints no velocity or effort limit: nothing to honour."""

from __future__ import annotations

import math

from ..progress import LOGGER
from .model import Robot

__all__ = ["warn_unlimited_joints"]


def warn_unlimited_joints(robot: Robot) -> None:
    """Warn when some joint has no velocity or no effort limit in the URDF.

    Plans honour the URDF's velocity (rad/s or m/s) and effort (N m or N) limits; where it
    gives none (no ``<limit>`` element, or 0), a plan may ask any rate or torque of that
    joint (ETS-VII's URDF, planned in 1 ms: 1e4 rad/s and 1e10 N m). Named, not refused.
    """
    missing = [
        j.name
        for j in robot.joints
        if not (math.isfinite(j.velocity_limit) and math.isfinite(j.effort_limit))
    ]
    if missing:
        LOGGER.warning(
            "the URDF gives no velocity or no effort limit for %s: no such limit is imposed "
            "there (add <limit velocity=... effort=...> to the joint to impose one)",
            ", ".join(repr(name) for name in missing),
        )

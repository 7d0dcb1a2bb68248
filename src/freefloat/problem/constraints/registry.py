"""The constraints freefloat knows by name, and the default list a plan honours.

A new constraint is one module with a :class:`~.base.Constraint` subclass plus one entry
here; solvers, verification and the plan file pick it up from the list.
"""

from __future__ import annotations

from .base import Constraint
from .joint_position import JointPositionLimits
from .joint_velocity import JointVelocityLimits

__all__ = ["CONSTRAINTS", "default_constraints"]

#: Constraint classes by name.
CONSTRAINTS: dict[str, type[Constraint]] = {
    JointPositionLimits.name: JointPositionLimits,
    JointVelocityLimits.name: JointVelocityLimits,
}


def default_constraints() -> list[Constraint]:
    """The constraints every plan honours: joint position limits and joint velocity limits."""
    return [JointPositionLimits(), JointVelocityLimits()]

"""Path constraints: one interface (:class:`Constraint`), one module per constraint."""

from .base import (
    DEFAULT_INSTANTS,
    Constraint,
    ConstraintRows,
    DurationScaledLimit,
    Excess,
    LimitPeak,
)
from .base_pointing import BasePointing
from .base_swing import BaseSwing
from .clearance import Clearance
from .end_effector_cone import EndEffectorCone
from .joint_effort import JointEffortLimits
from .joint_position import JointPositionLimits
from .joint_velocity import JointVelocityLimits
from .registry import (
    CONSTRAINTS,
    constraint_from_record,
    default_constraints,
    recorded_constraints,
    scenario_constraints,
)

__all__ = [
    "CONSTRAINTS",
    "DEFAULT_INSTANTS",
    "BasePointing",
    "BaseSwing",
    "Clearance",
    "Constraint",
    "ConstraintRows",
    "DurationScaledLimit",
    "EndEffectorCone",
    "Excess",
    "JointEffortLimits",
    "JointPositionLimits",
    "JointVelocityLimits",
    "LimitPeak",
    "constraint_from_record",
    "default_constraints",
    "recorded_constraints",
    "scenario_constraints",
]

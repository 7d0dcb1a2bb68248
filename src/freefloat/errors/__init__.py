"""The exceptions freefloat raises: one root, :class:`FreeFloatError`, and subclasses with data.

Every message is a single line that names the problem and says what would be valid, so that
the command line can print it as it is (exit code 2) and a caller can test it. The motion
errors (limits needing a longer duration, goals out of reach) are in :mod:`.motion`, those of
one configuration (limits, collisions, constraints of the pose, locks) in :mod:`.pose`. One
warning class, :class:`UnitsWarning`, is issued through :mod:`warnings` for a value accepted but
likely written in the wrong unit.
"""

from ..excerpts import EXCERPT_CHARS, excerpt
from .base import (
    AmbiguousEndEffectorError,
    FileError,
    FreeFloatError,
    InfeasibleError,
    InputError,
    InputLimitError,
    ModelError,
    PlanFileError,
    PlanMismatchError,
    PluginError,
    ScenarioError,
    SolverError,
    UnitsWarning,
    UnknownNameError,
    VerificationError,
    ViewerError,
)
from .motion import (
    DurationLimitError,
    EffortLimitError,
    UnreachableAttitudeError,
    UnreachableGoalError,
    VelocityLimitError,
)
from .pose import (
    CollisionError,
    EndpointError,
    GoalAttitudeError,
    JointLimitError,
    LockedJointError,
)

__all__ = [
    "EXCERPT_CHARS",
    "AmbiguousEndEffectorError",
    "CollisionError",
    "DurationLimitError",
    "EffortLimitError",
    "EndpointError",
    "FileError",
    "FreeFloatError",
    "GoalAttitudeError",
    "InfeasibleError",
    "InputError",
    "InputLimitError",
    "JointLimitError",
    "LockedJointError",
    "ModelError",
    "PlanFileError",
    "PlanMismatchError",
    "PluginError",
    "ScenarioError",
    "SolverError",
    "UnitsWarning",
    "UnknownNameError",
    "UnreachableAttitudeError",
    "UnreachableGoalError",
    "VelocityLimitError",
    "VerificationError",
    "ViewerError",
    "excerpt",
]

"""The constraints freefloat knows by name, and the default list a plan honours.

A new constraint is one module with a :class:`~.base.Constraint` subclass plus one entry
here; solvers, verification and the plan file pick it up from the list.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from pathlib import Path

from ...robot.collision import CollisionModel, Obstacle, collision_model, known_srdf
from ...robot.model import Robot
from ..scenario import Scenario
from .base import Constraint
from .clearance import Clearance
from .joint_effort import JointEffortLimits
from .joint_position import JointPositionLimits
from .joint_velocity import JointVelocityLimits

__all__ = [
    "CONSTRAINTS",
    "cached_collision_model",
    "clearance_constraint",
    "default_constraints",
    "scenario_constraints",
]

#: Constraint classes by name.
CONSTRAINTS: dict[str, type[Constraint]] = {
    JointPositionLimits.name: JointPositionLimits,
    JointVelocityLimits.name: JointVelocityLimits,
    JointEffortLimits.name: JointEffortLimits,
    Clearance.name: Clearance,
}


def default_constraints() -> list[Constraint]:
    """The constraints every plan honours: joint position, velocity and effort limits."""
    return [JointPositionLimits(), JointVelocityLimits(), JointEffortLimits()]


def scenario_constraints(scenario: Scenario) -> list[Constraint]:
    """The constraints a scenario's plan honours: the defaults, and clearance when checked.

    Clearance is added when ``[safety] check`` is on (the default) and the robot's collision
    geometry (with the scenario's obstacles and payload) has pairs to check.
    """
    constraints = default_constraints()
    safety = scenario.safety
    if safety.check:
        srdf = safety.srdf or known_srdf(scenario.robot)
        clearance = clearance_constraint(scenario.robot, srdf, safety.obstacles, safety.margin)
        if clearance is not None:
            constraints.append(clearance)
    return constraints


def clearance_constraint(
    robot: Robot, srdf: str | Path | None, obstacles: Sequence[Obstacle], margin: float
) -> Clearance | None:
    """Clearance of ``margin`` (m) on the robot's collision model; None when it has no pairs.

    The collision model (SRDF pairs removed, obstacles added) is built once per robot.
    """
    model = cached_collision_model(robot, srdf, obstacles)
    return Clearance(model, margin) if model.n_pairs else None


def cached_collision_model(
    robot: Robot, srdf: str | Path | None, obstacles: Sequence[Obstacle]
) -> CollisionModel:
    """The robot's collision model with an SRDF's pairs removed and obstacles added, built once."""
    models = _MODELS.setdefault(robot, {})
    key = (None if srdf is None else str(srdf), tuple(obstacles))
    if key not in models:
        models[key] = collision_model(robot, srdf, obstacles)
    return models[key]


#: Collision models per robot (by SRDF and obstacles), built once; entries go with the robot.
_MODELS: weakref.WeakKeyDictionary[
    Robot, dict[tuple[str | None, tuple[Obstacle, ...]], CollisionModel]
] = weakref.WeakKeyDictionary()

"""The constraints freefloat knows by name, and the default list a plan honours.

A new constraint is one module with a :class:`~.base.Constraint` subclass plus one entry
here; solvers, verification and the plan file pick it up from the list.
"""

from __future__ import annotations

import weakref

from ...robot.collision import CollisionModel, Obstacle, collision_model, known_srdf
from ...robot.model import Robot
from ..scenario import Scenario
from .base import Constraint
from .clearance import Clearance
from .joint_position import JointPositionLimits
from .joint_velocity import JointVelocityLimits

__all__ = ["CONSTRAINTS", "default_constraints", "scenario_constraints"]

#: Constraint classes by name.
CONSTRAINTS: dict[str, type[Constraint]] = {
    JointPositionLimits.name: JointPositionLimits,
    JointVelocityLimits.name: JointVelocityLimits,
    Clearance.name: Clearance,
}


def default_constraints() -> list[Constraint]:
    """The constraints every plan honours: joint position limits and joint velocity limits."""
    return [JointPositionLimits(), JointVelocityLimits()]


def scenario_constraints(scenario: Scenario) -> list[Constraint]:
    """The constraints a scenario's plan honours: the defaults, and clearance when checked.

    Clearance is added when ``[safety] check`` is on (the default) and the robot's collision
    geometry (with the scenario's obstacles and payload) has pairs to check.
    """
    constraints = default_constraints()
    safety = scenario.safety
    if safety.check:
        srdf = safety.srdf or known_srdf(scenario.robot)
        models = _MODELS.setdefault(scenario.robot, {})
        key = (None if srdf is None else str(srdf), safety.obstacles)
        if key not in models:
            models[key] = collision_model(scenario.robot, srdf, safety.obstacles)
        if models[key].n_pairs:
            constraints.append(Clearance(models[key], safety.margin))
    return constraints


#: Collision models per robot (by SRDF and obstacles), built once; entries go with the robot.
_MODELS: weakref.WeakKeyDictionary[
    Robot, dict[tuple[str | None, tuple[Obstacle, ...]], CollisionModel]
] = weakref.WeakKeyDictionary()

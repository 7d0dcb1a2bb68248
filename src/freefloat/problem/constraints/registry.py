"""The constraints freefloat knows by name, and the default list a plan honours.

A new constraint is one module with a :class:`~.base.Constraint` subclass plus one entry in
:data:`CONSTRAINTS` (or, from another package, one ``freefloat.constraints`` entry point:
:mod:`freefloat.plugins`); from that entry a scenario reads its ``[constraints.<name>]``
table, a plan records it (``constraints``, with :meth:`~.base.Constraint.to_record`),
``freefloat verify`` rebuilds it (:func:`constraint_from_record`) and the schemas list its name.

Clearance is the exception for now: its collision model is built from the robot, the SRDF and
the obstacles, so it is described by the scenario's ``[safety]`` and the plan's ``safety``
record (:data:`SAFETY_RECORDED`), not by a constraint record.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

from ...errors import InputError, ScenarioError, UnknownNameError
from ...plugins import Registry, plugin_class
from ...robot.collision import CollisionModel, Obstacle, collision_model, known_srdf
from ...robot.geometry import BuiltPerSource
from ...robot.model import Robot
from .base import Constraint
from .base_pointing import BasePointing
from .base_swing import BaseSwing
from .clearance import Clearance
from .end_effector_cone import EndEffectorCone
from .joint_effort import JointEffortLimits
from .joint_position import JointPositionLimits
from .joint_velocity import JointVelocityLimits


class ScenarioSafety(Protocol):
    """What :func:`scenario_constraints` reads of a scenario's ``[safety]`` (m)."""

    @property
    def check(self) -> bool: ...
    @property
    def margin(self) -> float: ...
    @property
    def srdf(self) -> Path | None: ...
    @property
    def obstacles(self) -> tuple[Obstacle, ...]: ...


class ScenarioLike(Protocol):
    """What :func:`scenario_constraints` reads of a scenario.

    A protocol, so that the scenario module (which reads constraint tables) is not imported.
    """

    @property
    def robot(self) -> Robot: ...
    @property
    def safety(self) -> ScenarioSafety: ...
    @property
    def constraints(self) -> tuple[Constraint, ...]: ...


__all__ = [
    "CONSTRAINTS",
    "SAFETY_RECORDED",
    "cached_collision_model",
    "clearance_constraint",
    "constraint_from_record",
    "default_constraints",
    "recorded_constraints",
    "scenario_constraints",
]

#: Constraint classes by name: the one list (scenario keys, plan records, verify, schemas);
#: with those installed packages declare in the ``freefloat.constraints`` entry point group.
CONSTRAINTS: Registry[type[Constraint]] = Registry(
    "constraint",
    {
        cls.name: cls
        for cls in (
            JointPositionLimits,
            JointVelocityLimits,
            JointEffortLimits,
            Clearance,
            EndEffectorCone,
            BaseSwing,
            BasePointing,
        )
    },
    plugin_class(Constraint, "constraint"),
)

#: Constraints described by the ``[safety]`` table and the plan's ``safety`` record instead of
#: a constraint record (see the module docstring).
SAFETY_RECORDED = (Clearance.name,)


def recorded_constraints() -> list[str]:
    """Names of the constraints a scenario table or a plan record may name, in order."""
    return [name for name in CONSTRAINTS if name not in SAFETY_RECORDED]


def constraint_from_record(name: str, record: Mapping[str, Any]) -> Constraint:
    """The constraint ``name`` with the parameters of its record (scenario table, plan record).

    Raises:
        UnknownNameError: ``name`` is not a recorded constraint (lists the valid ones).
        InputError: a bad parameter (named by the constraint).
    """
    if name not in CONSTRAINTS or name in SAFETY_RECORDED:
        raise UnknownNameError("constraint", name, recorded_constraints())
    if not isinstance(record, Mapping):
        raise InputError(f"constraint {name!r}: its parameters must be a table, got {record!r}")
    return CONSTRAINTS[name].from_record(record)


def default_constraints() -> list[Constraint]:
    """The constraints every plan honours: joint position, velocity and effort limits."""
    return [JointPositionLimits(), JointVelocityLimits(), JointEffortLimits()]


def scenario_constraints(scenario: ScenarioLike) -> list[Constraint]:
    """The constraints a scenario's plan honours.

    The defaults, its ``[constraints.<name>]`` tables, and clearance when checked.
    Clearance is added when ``[safety] check`` is on (the default) and the robot's collision
    geometry (with the scenario's obstacles and payload) has pairs to check.

    Raises:
        ScenarioError: a keep-out object no moving body can be checked against (clearance
            on, and no body with collision geometry in a pair with it): it would be ignored.
    """
    constraints = [*default_constraints(), *scenario.constraints]
    safety = scenario.safety
    if safety.check:
        srdf = safety.srdf or known_srdf(scenario.robot)
        unpaired = cached_collision_model(scenario.robot, srdf, safety.obstacles).unpaired_obstacles
        if unpaired:
            raise ScenarioError(
                f"keep-out object{'s' if len(unpaired) > 1 else ''} "
                f"{', '.join(repr(n) for n in unpaired)} cannot be kept clear: no moving body "
                f"of {scenario.robot.name} has collision geometry to check against it; add "
                "<collision> elements to its links, or remove the object, or set [safety] "
                "check = false"
            )
        clearance = clearance_constraint(scenario.robot, srdf, safety.obstacles, safety.margin)
        if clearance is not None:
            constraints.append(clearance)
    return constraints


def clearance_constraint(
    robot: Robot, srdf: str | Path | None, obstacles: Sequence[Obstacle], margin: float
) -> Clearance | None:
    """Clearance of ``margin`` (m) on the robot's collision model; None when it has no pairs.

    The collision model (SRDF pairs removed, obstacles added) is built once per source.
    """
    model = cached_collision_model(robot, srdf, obstacles)
    return Clearance(model, margin) if model.n_pairs else None


def cached_collision_model(
    robot: Robot, srdf: str | Path | None, obstacles: Sequence[Obstacle]
) -> CollisionModel:
    """The robot's collision model with an SRDF's pairs removed and obstacles added.

    Built once per source in a process (:class:`~freefloat.robot.geometry.BuiltPerSource`):
    fresh loads of one unchanged URDF share it. Its distances do not depend on what was asked
    before (its kept bounds change only which pairs a query measures).
    """
    return _MODELS.get(robot, srdf, obstacles)


#: Collision models per source (URDF, kinematic tree, mesh files, SRDF, obstacles).
_MODELS: BuiltPerSource[CollisionModel] = BuiltPerSource(collision_model)

"""One configuration of a scenario's robot checked: joint limits, clearance, constraints.

:func:`check_configuration` is what ``freefloat check`` prints: per joint its value and room to
either URDF limit, and, when the scenario checks clearance, the closest body pairs of the
collision model (signed distances, m: negative when they overlap) and whether the smallest one
keeps the scenario's margin; and each scenario constraint the configuration alone decides (an
end-effector cone). Nothing is planned and nothing is written (except an inline
servicer's URDF into its cache).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .problem.constraints import Clearance, scenario_constraints
from .problem.endpoints import at_end_attitude, at_rest
from .problem.limits import MAX_ANGLE_DEG, MAX_LENGTH_M, check_number
from .problem.radians_hint import warn_if_radians
from .problem.scenario import Scenario

__all__ = [
    "ConfigurationReport",
    "JointRoom",
    "PoseConstraint",
    "check_configuration",
    "parse_joints",
]

#: A plain decimal number in ASCII (no underscores, no other scripts' digits).
_NUMBER = re.compile(
    r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|[+-]?(nan|inf)", re.IGNORECASE | re.ASCII
)

#: Closest pairs a report lists.
CLOSEST_PAIRS = 5


@dataclass(frozen=True)
class JointRoom:
    """One joint's value and its room to the URDF limits.

    Attributes:
        name: the joint.
        value: its value (rad or m).
        lower: lower limit (rad or m; -inf for a continuous joint).
        upper: upper limit (same unit).
        angular: whether the unit is rad (else m).
    """

    name: str
    value: float
    lower: float
    upper: float
    angular: bool

    @property
    def room(self) -> float:
        """Distance to the nearer limit (rad or m); negative outside the limits."""
        return min(self.value - self.lower, self.upper - self.value)


@dataclass(frozen=True)
class PoseConstraint:
    """A scenario constraint the configuration alone decides, at the configuration.

    Attributes:
        name: the constraint (its table ``[constraints.<name>]``).
        excess: how far beyond it (its unit; <= its tolerance when it holds).
        detail: its own account (an angle).
        holds: whether the excess is within its tolerance.
    """

    name: str
    excess: float
    detail: str
    holds: bool


@dataclass(frozen=True)
class ConfigurationReport:
    """A configuration's limits and clearance.

    Attributes:
        joints: per joint, value and room.
        pairs: the closest checked pairs, ``(name "a / b", signed distance m)``, nearest first;
            empty when the scenario checks no clearance.
        margin: the clearance margin (m), or None when clearance is not checked.
        constraints: the scenario's constraints the configuration alone decides (an
            end-effector cone), at the configuration.
    """

    joints: tuple[JointRoom, ...]
    pairs: tuple[tuple[str, float], ...]
    margin: float | None
    constraints: tuple[PoseConstraint, ...] = ()

    @property
    def within_constraints(self) -> bool:
        """Every constraint of the configuration alone holds there."""
        return all(c.holds for c in self.constraints)

    @property
    def within_limits(self) -> bool:
        """Every joint inside its limits."""
        return all(j.room >= 0.0 for j in self.joints)

    @property
    def clear(self) -> bool:
        """The smallest clearance keeps the margin (True when clearance is not checked)."""
        return self.margin is None or not self.pairs or self.pairs[0][1] >= self.margin


def parse_joints(text: str, scenario: Scenario) -> np.ndarray:
    """``start``, ``goal`` or comma-separated joint values (deg; m for prismatic) in rad/m."""
    if text == "start":
        return np.asarray(scenario.start, dtype=float)
    if text == "goal":
        return np.asarray(scenario.goal, dtype=float)
    joints = scenario.robot.joints
    parts = text.replace(" ", "").split(",")
    if not all(_NUMBER.fullmatch(p) for p in parts):  # float() takes 1_0 and other digits
        raise InputError(
            f"--at must be start, goal or {len(joints)} comma-separated numbers "
            f"(deg; m for prismatic joints), got {text!r}"
        )
    values = [float(p) for p in parts]
    if len(values) != len(joints):
        raise InputError(
            f"--at needs {len(joints)} finite value{'s' if len(joints) != 1 else ''}, one per "
            "joint "
            f"({', '.join(j.name for j in joints)}), got {len(values)}"
        )
    bad = next((j.name for v, j in zip(values, joints, strict=True) if not math.isfinite(v)), None)
    if bad is not None:
        raise InputError(f"--at needs finite values, got {text!r} (joint {bad!r} is not finite)")
    for value, joint in zip(values, joints, strict=True):
        high, unit = (MAX_ANGLE_DEG, "deg") if joint.angular else (MAX_LENGTH_M, "m")
        check_number(value, f"--at joint {joint.name!r}", high, unit)
    warn_if_radians({j.name: v for v, j in zip(values, joints, strict=True) if j.angular}, "--at")
    return np.array(
        [math.radians(v) if j.angular else v for v, j in zip(values, joints, strict=True)]
    )


def check_configuration(
    scenario: Scenario, joints: np.ndarray, at: str = ""
) -> ConfigurationReport:
    """Limits, closest pairs and clearance of the scenario's robot at ``joints`` (rad or m).

    ``at``: ``"start"`` or ``"goal"`` when the joints are that end's: the constraints of its
    attitude (the spacecraft's swing or pointing) are judged there too.
    """
    scenario.write_robot()  # the goal is not solved: the joints asked about are given
    robot = scenario.robot
    rooms = tuple(
        JointRoom(j.name, float(v), j.lower, j.upper, j.angular)
        for j, v in zip(robot.joints, joints, strict=True)
    )
    constraints = scenario_constraints(scenario)
    posed = [
        PoseConstraint(constraint.name, excess.value, excess.detail, holds)
        for constraint, excess, holds in at_rest(constraints, robot, joints)
    ]
    if at in ("start", "goal"):
        posed += [
            PoseConstraint(constraint.name, excess.value, f"{at} attitude: {excess.detail}", ok)
            for constraint, excess, ok in at_end_attitude(scenario, constraints, at)
        ]
    clearance = next((c for c in constraints if isinstance(c, Clearance)), None)
    if clearance is None or not clearance.applies_to(robot):
        return ConfigurationReport(rooms, (), None, tuple(posed))
    model = clearance.model
    values = np.asarray(model.distances(np.asarray(joints, dtype=float)).values)
    order = np.argsort(values)[:CLOSEST_PAIRS]
    pairs = tuple((model.names[k], float(values[k])) for k in order)
    return ConfigurationReport(rooms, pairs, clearance.margin, tuple(posed))

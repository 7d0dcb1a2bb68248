"""Start and goal checked before any search: limits, clearance, constraints of the pose.

Inside the joint limits, clear of collisions, and within every constraint the configuration
alone decides (an end-effector cone).

``plan`` and ``reach`` refuse the same scenarios for the same reason: a motion whose start or
goal breaks a limit, the clearance margin or such a constraint cannot be planned, whatever
the attitude asked.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import CollisionError, EndpointError, GoalAttitudeError
from ..physics.attitude import quat_exp, quat_multiply, relative_quat
from ..robot.collision import CollisionModel, clearance_at
from ..robot.designed_bodies import designed_bodies
from ..robot.geometry import OBSTACLE_PREFIX
from ..robot.model import Robot
from ..robot.payload import PAYLOAD_LINK
from .build import check_joint_limits
from .constraints import Clearance, Constraint, Excess
from .scenario import Scenario
from .simple_bound import first_crossing

__all__ = [
    "at_attitude",
    "at_end_attitude",
    "at_rest",
    "check_end_attitudes",
    "check_endpoints",
    "goal_turn_limit",
]


def check_endpoints(
    scenario: Scenario, constraints: Sequence[Constraint], chosen_goal: bool = False
) -> None:
    """Refuse a start or goal outside the joint limits, then one too close to a collision.

    Limits first: an overlap of a pose the arm cannot take says nothing useful. Each refusal
    names the joint or the pair; ``chosen_goal``: the goal joints came from inverse
    kinematics of an end-effector goal (the refusal asks to move that goal).

    Raises:
        JointLimitError: the start or goal joints outside their limits (rad or m).
        CollisionError: a checked pair of the start or goal closer than the clearance margin
            of a :class:`Clearance` among ``constraints`` (m).
        EndpointError: the start or goal breaks a constraint of the configuration alone
            (:meth:`Constraint.at_rest`: an end-effector cone), which no path can keep.
    """
    for where, values in (("start", scenario.start), ("goal", scenario.goal)):
        check_joint_limits(scenario.robot, np.asarray(values, dtype=float), where)
    ends = (("start", scenario.start), ("goal", scenario.goal))
    for constraint in constraints:
        if isinstance(constraint, Clearance) and constraint.applies_to(scenario.robot):
            for where, joints in ends:
                found = clearance_at(constraint.model, joints)
                if found.distance < constraint.margin:
                    chosen = chosen_goal and where == "goal"
                    why = _swing_note(constraint, found.pair)
                    model = constraint.model
                    fixed = _fixed_distance(model, found.pair, found.distance)
                    objects = [model.geometry.geometryObjects[g] for g in model.pairs[found.pair]]
                    keep_out = any(o.name.startswith(OBSTACLE_PREFIX) for o in objects)
                    raise CollisionError(
                        where,
                        found.name,
                        found.distance,
                        constraint.margin,
                        chosen,
                        why,
                        fixed,
                        keep_out,
                    )
    for where, joints in ends:  # the configuration alone decides, for every path
        for constraint, excess, holds in at_rest(constraints, scenario.robot, joints):
            if not holds:
                chosen = chosen_goal and where == "goal"
                raise EndpointError(where, constraint.name, excess.value, excess.detail, chosen)


def check_end_attitudes(scenario: Scenario, constraints: Sequence[Constraint]) -> None:
    """Refuse a start or goal attitude that breaks a constraint of the attitude.

    Every path starts and ends there.

    Raises:
        GoalAttitudeError: the start or goal attitude breaks a constraint
            (:meth:`Constraint.at_attitude`: the spacecraft's swing or pointing).
    """
    for where in ("start", "goal"):
        for constraint, excess, holds in at_end_attitude(scenario, constraints, where):
            if not holds:
                raise GoalAttitudeError(constraint.name, excess.value, excess.detail, where)


def at_end_attitude(
    scenario: Scenario, constraints: Sequence[Constraint], where: str
) -> list[tuple[Constraint, Excess, bool]]:
    """The constraints the start or goal attitude (``where``) alone decides.

    Each with its excess there (:meth:`Constraint.at_attitude`) and whether that is at most
    rounding (:data:`END_ROUNDING`).
    """
    relative = (
        relative_quat(scenario.start_attitude, scenario.goal_attitude)
        if where == "goal"
        else np.array([0.0, 0.0, 0.0, 1.0])
    )
    return at_attitude(constraints, relative)


def at_attitude(
    constraints: Sequence[Constraint], relative: np.ndarray
) -> list[tuple[Constraint, Excess, bool]]:
    """The constraints an attitude alone decides, with their excesses and whether they hold.

    ``relative``: the attitude relative to the start (``[x, y, z, w]``); holds: beyond by at
    most rounding (:data:`END_ROUNDING`).
    """
    found = []
    for constraint in constraints:
        excess = constraint.at_attitude(relative)
        if excess is not None:
            found.append((constraint, excess, excess.value <= END_ROUNDING))
    return found


#: How far beyond a constraint of the attitude a start or goal may lie (its unit): rounding
#: only. Not its verification tolerance: rows near the end ask the path to stay inside, which
#: a path ending beyond the bound cannot.
END_ROUNDING = 1e-12


def goal_turn_limit(
    constraints: Sequence[Constraint], moved: np.ndarray, axis: np.ndarray, turn: float
) -> float:
    """How far (rad, at most ``turn``) a goal may turn about ``axis`` from ``moved``.

    As far as it breaks no constraint of the goal attitude (:meth:`Constraint.at_attitude`,
    in rad: the turn from the start and a boresight's angle each change by at most the turn
    about ``axis``, so :func:`.simple_bound.first_crossing` applies). ``moved``: an attitude
    relative to the start (the drift attitude's), ``[x, y, z, w]``; ``axis``: a unit axis in
    its frame. 0 when ``moved`` itself breaks one.
    """
    judged = [c for c in constraints if c.at_attitude(moved) is not None]
    if not judged:
        return turn
    axis = np.asarray(axis, dtype=float)

    def room(theta: float) -> float:
        relative = quat_multiply(moved, quat_exp(theta * axis))
        return -max(c.at_attitude(relative).value for c in judged)  # type: ignore[union-attr]

    return first_crossing(room, turn)


def at_rest(
    constraints: Sequence[Constraint], robot: Robot, joints: np.ndarray
) -> list[tuple[Constraint, Excess, bool]]:
    """The constraints the configuration ``joints`` (rad or m) alone decides, at it.

    Each with its excess there and whether that is within its tolerance
    (:meth:`Constraint.at_rest`).
    """
    found = []
    for constraint in constraints:
        excess = constraint.at_rest(robot, np.asarray(joints, dtype=float))
        if excess is not None:
            found.append((constraint, excess, excess.value <= constraint.tolerance))
    return found


def _swing_note(constraint: Clearance, pair: int) -> str:
    """Why a parent and child pair (its index) is checked: its joint swings one into the other."""
    model = constraint.model
    robot = model.robot
    if not robot.urdf_text:
        return ""
    objects = model.geometry.geometryObjects
    pair_objects = [objects[g] for g in model.pairs[pair]]
    if any(o.name.startswith(OBSTACLE_PREFIX) for o in pair_objects):  # never parent nor child
        return ""
    links = [robot.model.frames[o.parentFrame].name for o in pair_objects]
    if PAYLOAD_LINK in links or not designed_bodies(robot.urdf_text).adjacent(*links):
        return ""
    return (
        "parent and child, checked because the joint between them swings one into the other "
        "(docs/clearance.md); if they touch only where they are joined, start the moving "
        "link's collision shape clear of the other, or disable the pair in an SRDF"
    )


#: Configurations a refused pair is measured at to tell whether any joints move it (a count).
FIXED_PROBES = 16


def _fixed_distance(model: CollisionModel, pair: int, distance: float) -> bool:
    """Whether no joint values change pair ``pair``'s ``distance`` (m), measured at rest.

    A refusal then asks for no joints to move. Two links that only turn about an axis that
    keeps them apart alike (a sphere or a cylinder about that axis, on ETS-VII's links) are
    such a pair. Measured at :data:`FIXED_PROBES` configurations drawn within the joint
    limits (seeded; a continuous joint over a turn): fixed when none differs from
    ``distance`` by more than 1e-9 m.
    """
    joints = model.robot.joints
    low = np.array([j.lower if math.isfinite(j.lower) else -math.pi for j in joints])
    high = np.array([j.upper if math.isfinite(j.upper) else math.pi for j in joints])
    probes = np.random.default_rng(0).uniform(low, high, (FIXED_PROBES, len(joints)))
    found = [model.pair_distances(q, [pair])[0] for q in probes]
    return bool(np.all(np.abs(np.asarray(found) - distance) <= 1e-9))

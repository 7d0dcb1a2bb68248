"""A scenario file's tables read and checked: keys, start and goal, path options, payload.

Pure parsing (degrees at this edge, radians inside; metres): every key checked against the
format, every number against its limit; no file is written and no inverse kinematics runs
(that is :meth:`~freefloat.problem.scenario.Scenario.resolved`). The format is described in
:mod:`freefloat.problem.scenario`; ``[safety]``, ``[[obstacles]]`` and ``[constraints]`` are
read by :mod:`freefloat.problem.scenario_safety`, ``[robot]`` by
:mod:`freefloat.problem.robot_table`.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ScenarioError, excerpt
from ..files import other_kind_hint, read_text_file
from ..physics.attitude import quat_from_zyx, quat_to_matrix
from ..robot.model import Robot
from .limits import MAX_ANGLE_DEG, MAX_LENGTH_M, MAX_SCENARIO_BYTES, check_extra
from .objectives.registry import DEFAULT_OBJECTIVE, OBJECTIVES
from .quaternion_hint import warn_if_odd_quaternion
from .radians_hint import warn_if_radians
from .robot_table import RobotSource, check_keys, number, numbers, scenario_errors

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "GOAL_KEYS",
    "PATH_KEYS",
    "STATE_KEYS",
    "TOP_KEYS",
    "CartesianGoal",
    "PathOptions",
    "States",
    "check_top_keys",
    "end_effector_names",
    "path_options",
    "read_toml",
    "state_tables",
]

#: Keys of a scenario file, of its tables and of a goal frame's table.
TOP_KEYS = (
    "robot",
    "duration",
    "end_effector",
    "end_effectors",
    "start",
    "goal",
    "path",
    "safety",
    "obstacles",
    "payload",
    "constraints",
)
STATE_KEYS = ("joints", "base_zyx_deg", "base_quaternion_xyzw")
GOAL_KEYS = (*STATE_KEYS, "end_effector_xyz", "end_effector_rpy_deg", "end_effectors")
_FRAME_GOAL_KEYS = ("xyz", "rpy_deg")
PATH_KEYS = ("extra", "max_deviation_deg", "allow_full_turns", "objective", "raise_freedom")


def read_toml(path: Path, what: str) -> dict[str, Any]:
    """The parsed tables of a TOML file; ``what`` names it in messages ("scenario"...).

    At most :data:`~freefloat.problem.limits.MAX_SCENARIO_BYTES` are read, from a regular
    file only.

    Raises:
        ScenarioError: missing, unreadable, not a regular file, too large, or not TOML.
    """
    text = read_text_file(path, what, MAX_SCENARIO_BYTES, ScenarioError)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        hint = other_kind_hint(path, text[:200], "toml")
        reason = excerpt(str(exc), 200)[1:-1]
        raise ScenarioError(f"{path}: invalid TOML ({reason}){hint}") from None
    except RecursionError:
        raise ScenarioError(
            f"{path}: arrays or tables nested too deeply for freefloat to read"
        ) from None
    except ValueError as exc:  # an integer of more digits than Python converts
        raise ScenarioError(f"{path}: invalid TOML ({excerpt(str(exc), 200)[1:-1]})") from None


def check_top_keys(data: Mapping[str, Any]) -> None:
    """Refuse an unknown top-level key or a missing required one."""
    check_keys(data, TOP_KEYS, "the scenario")
    for key in ("robot", "duration", "start", "goal"):
        if key not in data:
            raise ScenarioError(
                f"missing required key {key!r} (required: robot, duration, [start], [goal])"
            )


@dataclass(frozen=True)
class CartesianGoal:
    """An end-effector goal, from the system CM in the inertial frame.

    Attributes:
        position: wanted end-effector position (m).
        rotation: wanted end-effector orientation (3 x 3), or None for position only.
    """

    position: np.ndarray
    rotation: np.ndarray | None = None


@dataclass(frozen=True)
class States:
    """The ``[start]`` and ``[goal]`` tables, read.

    Attributes:
        start_joints: ``{joint: value}`` at t = 0 (rad, or m for prismatic joints).
        goal_joints: ``{joint: value}`` at t = T (rad or m): with Cartesian goals, only the
            joint goals given.
        start_attitude: base attitude at t = 0, quaternion ``[x, y, z, w]``.
        goal_attitude: wanted base attitude at t = T, quaternion ``[x, y, z, w]``.
        goal_poses: Cartesian goals per end-effector frame (empty with joint goals).
    """

    start_joints: dict[str, float]
    goal_joints: dict[str, float]
    start_attitude: np.ndarray
    goal_attitude: np.ndarray
    goal_poses: dict[str, CartesianGoal]


def state_tables(
    data: Mapping[str, Any], robot: Robot, locked: Mapping[str, float] | None = None
) -> States:
    """The ``[start]`` and ``[goal]`` tables (deg, m) of ``data`` for ``robot``.

    Args:
        data: the scenario's tables.
        robot: its robot (joint names, kinds, end effector).
        locked: joints locked by ``[robot]`` (rad or m): named only at their locked value.
    """
    states: list[tuple[dict[str, float], np.ndarray]] = []
    goal_poses: dict[str, CartesianGoal] = {}
    for name in ("start", "goal"):
        table = data[name]
        if not isinstance(table, Mapping):
            raise ScenarioError(f"[{name}] must be a table")
        check_keys(table, GOAL_KEYS if name == "goal" else STATE_KEYS, f"[{name}]")
        quat = _attitude(table, name)
        if name == "goal" and "end_effector_xyz" in table:
            if "joints" in table or "end_effectors" in table:
                other = "joints" if "joints" in table else "end_effectors"
                raise ScenarioError(f"[goal] gives both {other} and end_effector_xyz; give one")
            goal_poses = {robot.end_effector: _cartesian_goal(table)}
            joints = {}
        elif name == "goal" and "end_effectors" in table:
            goal_poses = _frame_goals(table["end_effectors"])
            joints = _joint_table(robot, table, name, locked, partial=True)
        else:
            joints = _joint_table(robot, table, name, locked)
        states.append((joints, quat))
    (start, start_quat), (goal, goal_quat) = states
    return States(start, goal, start_quat, goal_quat, goal_poses)


def _attitude(table: Mapping[str, Any], name: str) -> np.ndarray:
    """The base attitude of ``[start]`` or ``[goal]`` as a unit quaternion ``[x, y, z, w]``."""
    if "base_zyx_deg" in table and "base_quaternion_xyzw" in table:
        raise ScenarioError(f"[{name}] gives both base_zyx_deg and base_quaternion_xyzw; give one")
    if "base_quaternion_xyzw" in table:
        quat = numbers(table["base_quaternion_xyzw"], 4, f"[{name}] base_quaternion_xyzw")
        if math.hypot(*quat) < 1e-9:  # hypot: 1e-300 squared would underflow to 0
            raise ScenarioError(
                f"[{name}] base_quaternion_xyzw has norm {math.hypot(*quat):.3g}, too near "
                "zero to be an attitude; give a unit quaternion [x, y, z, w]"
            )
        warn_if_odd_quaternion(quat, f"[{name}]")
        return quat / np.linalg.norm(quat)
    zyx = numbers(
        table.get("base_zyx_deg", [0.0, 0.0, 0.0]),
        3,
        f"[{name}] base_zyx_deg",
        MAX_ANGLE_DEG,
        "deg",
    )
    return quat_from_zyx(*np.radians(zyx))


@dataclass(frozen=True)
class PathOptions:
    """The ``[path]`` table, read (see :class:`~freefloat.problem.scenario.Scenario`).

    Attributes:
        extra: free coefficients per joint beyond the quintic; None lets the planner choose.
        max_deviation: one-unknown root bracket as largest path deviation (rad); None: default.
        allow_full_turns: a continuous joint may reach its goal the other way round.
        objective: the name of the objective.
        raise_freedom: an objective may add free coefficients beyond ``extra``.
    """

    extra: dict[str, int] | None = None
    max_deviation: float | None = None
    allow_full_turns: bool = False
    objective: str = DEFAULT_OBJECTIVE
    raise_freedom: bool = True


def _extra(raw: Any, robot: Robot, locked: Mapping[str, float]) -> dict[str, int]:
    """``[path] extra``: ``{joint: count}``, each joint the robot's and not locked."""
    if not isinstance(raw, Mapping):
        raise ScenarioError("[path] extra must be a table { joint = count, ... }")
    for name in raw:
        if name in locked:
            raise ScenarioError(
                f"[path] extra: joint {name!r} is locked ([robot] lock): it has no path to "
                "shape; leave it out of extra"
            )
        robot.joint(name, "[path] extra")
    return {n: scenario_errors(check_extra, c, f"[path] extra for {n!r}") for n, c in raw.items()}


def path_options(
    table: Any, robot: Robot, locked: Mapping[str, float] | None = None
) -> PathOptions:
    """The ``[path]`` table (deg) for ``robot``; an absent table gives the defaults.

    ``locked``: the joints ``[robot] lock`` fixed (rad or m), named as such when listed.
    """
    if not isinstance(table, Mapping):
        raise ScenarioError("[path] must be a table")
    check_keys(table, PATH_KEYS, "[path]")
    extra = _extra(table["extra"], robot, locked or {}) if "extra" in table else None
    max_deviation = None
    if "max_deviation_deg" in table:
        value = number(table["max_deviation_deg"], "[path] max_deviation_deg", MAX_ANGLE_DEG, "deg")
        if value <= 0.0:
            raise ScenarioError(f"[path] max_deviation_deg must be > 0, got {value:g}")
        max_deviation = math.radians(value)
    allow_full_turns = table.get("allow_full_turns", False)
    if not isinstance(allow_full_turns, bool):
        raise ScenarioError(
            f"[path] allow_full_turns must be true or false, got {excerpt(allow_full_turns)}"
        )
    objective = table.get("objective", DEFAULT_OBJECTIVE)
    if not isinstance(objective, str) or objective not in OBJECTIVES:
        raise ScenarioError(
            f"[path] objective must be one of {', '.join(OBJECTIVES)}, got {excerpt(objective)}"
        )
    raise_freedom = table.get("raise_freedom", True)
    if not isinstance(raise_freedom, bool):
        raise ScenarioError(
            f"[path] raise_freedom must be true or false, got {excerpt(raise_freedom)}"
        )
    return PathOptions(extra, max_deviation, allow_full_turns, objective, raise_freedom)


def _joint_table(
    robot: Robot,
    table: Mapping[str, Any],
    name: str,
    locked: Mapping[str, float] | None = None,
    partial: bool = False,
) -> dict[str, float]:
    """``{joint: value}`` in rad or m from a ``joints`` table in degrees (m for prismatic).

    Locked joints may be named with their locked value (and are left out); with ``partial``
    (Cartesian goals) any subset of the joints may be given.
    """
    locked = locked or {}
    raw = table.get("joints", {} if partial else None)
    if not isinstance(raw, Mapping):
        extra = " (or end_effector_xyz = [x, y, z])" if name == "goal" else ""
        raise ScenarioError(
            f"[{name}] needs joints = {{ name = value, ... }}{extra} "
            f"(joints: {', '.join(robot.joint_names)})"
        )
    joints: dict[str, float] = {}
    written: dict[str, float] = {}  # the revolute joints' values as written (deg)
    for joint_name, value in raw.items():
        if joint_name in locked:
            _check_locked(joint_name, value, locked[joint_name], name)
            continue
        joint = robot.joint(joint_name, f"[{name}] joints")
        limit, unit = (MAX_ANGLE_DEG, "deg") if joint.angular else (MAX_LENGTH_M, "m")
        amount = number(value, f"[{name}] joint {joint_name!r}", limit, unit)
        joints[joint_name] = math.radians(amount) if joint.angular else amount
        if joint.angular:
            written[joint_name] = amount
    if not partial:
        robot.vector(joints, f"[{name}] joints")  # every joint given
    warn_if_radians(written, f"[{name}]")
    return joints


def _check_locked(joint: str, value: Any, locked: float, where: str) -> None:
    """A locked joint named in ``[start]`` or ``[goal]`` must be at its locked value."""
    given = number(value, f"[{where}] joint {joint!r}", MAX_ANGLE_DEG)
    for amount, _unit in ((math.degrees(locked), "deg"), (locked, "m")):
        if abs(given - amount) <= 1e-9 * max(1.0, abs(amount)):
            return
    raise ScenarioError(
        f"[{where}] joint {joint!r} is {given:g} but the joint is locked at "
        f"{math.degrees(locked):.6g} deg (m for a prismatic joint); give that value or leave "
        "it out"
    )


def end_effector_names(data: Mapping[str, Any], source: RobotSource) -> tuple[str, ...]:
    """The end-effector frames a scenario names: ``end_effector(s)``, then goal frames.

    Empty when it names none and its robot brings none (the robot's default then applies).
    """
    if "end_effector" in data and "end_effectors" in data:
        raise ScenarioError("give end_effector or end_effectors, not both")
    named = data.get("end_effectors", data.get("end_effector"))
    if named is None:
        names = list(source.end_effectors)
    elif isinstance(named, str):
        names = [named]
    elif isinstance(named, list) and named and all(isinstance(n, str) for n in named):
        names = list(named)
    else:
        raise ScenarioError(
            f"end_effector must be a frame name (end_effectors a list of them), got "
            f"{excerpt(named)}"
        )
    goal = data.get("goal")
    frames = goal.get("end_effectors", {}) if isinstance(goal, Mapping) else {}
    if not isinstance(frames, Mapping):
        raise ScenarioError(
            "[goal] end_effectors must be tables [goal.end_effectors.<frame>] xyz = [x, y, z]"
        )
    return tuple(names + [f for f in frames if f not in names])


def _frame_goals(tables: Any) -> dict[str, CartesianGoal]:
    """``[goal.end_effectors.<frame>]`` tables (``xyz`` in m, ``rpy_deg``) as goals."""
    if not isinstance(tables, Mapping) or not tables:
        raise ScenarioError(
            "[goal] end_effectors must be tables [goal.end_effectors.<frame>] xyz = [x, y, z]"
        )
    goals = {}
    for frame, table in tables.items():
        where = f"[goal.end_effectors.{frame}]"
        if not isinstance(table, Mapping) or "xyz" not in table:
            raise ScenarioError(f"{where} needs xyz = [x, y, z] [m] (optional rpy_deg)")
        check_keys(table, _FRAME_GOAL_KEYS, where)
        goals[str(frame)] = _pose(table["xyz"], table.get("rpy_deg"), where)
    return goals


def _cartesian_goal(table: Mapping[str, Any]) -> CartesianGoal:
    """The Cartesian goal of ``end_effector_xyz`` (m) and optional ``end_effector_rpy_deg``."""
    return _pose(
        table["end_effector_xyz"], table.get("end_effector_rpy_deg"), "[goal] end_effector"
    )


def _pose(xyz_value: Any, rpy_value: Any, where: str) -> CartesianGoal:
    """A goal from ``xyz`` (m, from the system CM) and roll, pitch, yaw (deg) or None."""
    suffix = "_" if where.endswith("end_effector") else " "
    xyz = numbers(xyz_value, 3, f"{where}{suffix}xyz", MAX_LENGTH_M, "m")
    rotation = None
    if rpy_value is not None:
        rpy = numbers(rpy_value, 3, f"{where}{suffix}rpy_deg", MAX_ANGLE_DEG, "deg")
        rpy = np.radians(rpy)
        rotation = quat_to_matrix(quat_from_zyx(rpy[2], rpy[1], rpy[0]))
    return CartesianGoal(xyz, rotation)

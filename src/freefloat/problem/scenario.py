"""Scenarios: what to plan, read from a TOML file.

The file speaks degrees (joint angles, Euler angles) and metres (prismatic joints); a
:class:`Scenario` holds radians and metres. Format::

    robot = "planar_2dof"          # a shipped robot name, a URDF path relative to this file,
                                   # or a [robot] table composing a servicer (see below)
    duration = 10.0                # [s]
    end_effector = "ee"            # optional frame name; default: the tip of the longest
                                   # chain that is not a finger (or end_effectors = [...])
    [start]
    joints = { q1 = 80.0, q2 = 30.0 }      # deg (m for prismatic joints)
    base_zyx_deg = [-50.0, 0.0, 0.0]       # yaw, pitch, roll [deg]; optional, default zeros
    [goal]
    joints = { q1 = -60.0, q2 = 90.0 }     # or end_effector_xyz = [x, y, z] [m, from the CM]
                                           # (+ optional end_effector_rpy_deg = [r, p, y])
    base_zyx_deg = [0.0, 0.0, 0.0]         # or base_quaternion_xyzw = [x, y, z, w]
    [path]
    extra = { q2 = 1 }             # optional: free coefficients per joint beyond the quintic
    max_deviation_deg = 458.4      # optional: one-unknown root bracket, as path deviation [deg]
    allow_full_turns = false       # optional: continuous joints may go the other way round
    objective = "min_norm"         # optional: min_norm | min_effort | min_acceleration | min_length
    raise_freedom = true           # optional: an objective may raise the freedom beyond extra
    [constraints.end_effector_cone]        # optional: one table per extra constraint, by its
    axis = [1.0, 0.0, 0.0]                 # registered name, with its parameters (see
    direction = [1.0, 1.0, 0.0]            # freefloat.problem.constraints; the joint limits
    half_angle_deg = 60.0                  # are always honoured)

Safety, keep-out objects and a captured payload (all optional)::

    [safety]
    margin_m = 0.01                # required clearance [m] between checked bodies
    srdf = "ur5.srdf"              # pairs never checked; composed arms use example-robot-data's
    check = true                   # false: no clearance constraint at all
    [[obstacles]]                  # fixed to the spacecraft, in its frame
    name = "solar_panel"
    box = [0.02, 2.0, 0.8]         # or sphere = r, or capsule = [r, length]  [m]
    xyz = [0.0, 1.4, 0.0]          # [m]
    rpy_deg = [0.0, 0.0, 0.0]      # [deg]
    [payload]                      # rigidly held by the end effector
    mass = 300.0                   # [kg]
    com_xyz = [0.0, 0.0, 0.4]      # its CM in the end-effector frame [m]
    inertia = [20.0, 20.0, 20.0, 0.0, 0.0, 0.0]   # about that CM [kg m^2]
    box = [0.6, 0.6, 0.6]          # optional collision shape centred on the CM [m]

An inline servicer replaces ``robot = "..."`` with a table (composed in memory when read;
written to its content-addressed cache file when a plan is made, see :meth:`Scenario.write_robot`)::

    [robot]
    arm = "panda"                  # example-robot-data arm or URDF path
    base_mass = 100.0              # [kg]
    base_size = [0.6, 0.6, 0.6]    # [m]
    mount = [0.3, 0.0, 0.0]        # [m], in the spacecraft frame
    mount_rpy_deg = [0.0, 90.0, 0.0]   # optional [deg]; also base_inertia, lock, keep_gripper

Two or more arms (``arms = [{ arm = ..., mount = ..., prefix = ... }, ...]``), a URDF with
joints locked (``[robot] urdf = ...``, ``lock = [...]``): see
:mod:`freefloat.problem.robot_table`. Cartesian goals per end effector, solved together, with
any joint goals held and every other joint at its start value (docs/multi_arm.md)::

    [goal]
    joints = { right_elbow_joint = 80.0 }  # optional joint goals (deg)
    [goal.end_effectors.left_tool0]
    xyz = [0.48, 0.63, -0.43]              # [m], from the system CM
    rpy_deg = [0.0, 90.0, 0.0]             # optional [deg]
"""

from __future__ import annotations

import hashlib
import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import (
    FreeFloatError,
    InputError,
    ScenarioError,
    UnknownNameError,
    excerpt,
)
from ..files import absolute_path, atomic_write_text, read_text_file
from ..physics.attitude import quat_from_zyx, quat_to_matrix
from ..robot.collision import Obstacle
from ..robot.model import MAX_URDF_BYTES, Robot, load_robot, robots_dir
from ..robot.payload import Payload, attach_payload
from .constraints.base import Constraint
from .constraints.registry import constraint_from_record, default_constraints
from .limits import (
    MAX_ANGLE_DEG,
    MAX_LENGTH_M,
    MAX_MAGNITUDE,
    MAX_SCENARIO_BYTES,
    check_duration,
    check_extra,
    check_joint_count,
)
from .objectives.registry import DEFAULT_OBJECTIVE, OBJECTIVES
from .robot_table import (
    RobotSource,
    check_keys,
    number,
    numbers,
    robot_source,
    scenario_errors,
    servicer_cache_dir,
    triple,
)

if TYPE_CHECKING:
    from ..robot.compose import ServicerSpec

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "CartesianGoal",
    "Safety",
    "Scenario",
    "default_scenario_path",
    "read_toml",
    "servicer_cache_dir",
]

_TOP_KEYS = (
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
_SAFETY_KEYS = ("margin_m", "srdf", "check")
_OBSTACLE_KEYS = ("name", "box", "sphere", "capsule", "xyz", "rpy_deg")
_PAYLOAD_KEYS = ("mass", "com_xyz", "inertia", "box")
_STATE_KEYS = ("joints", "base_zyx_deg", "base_quaternion_xyzw")
_GOAL_KEYS = (*_STATE_KEYS, "end_effector_xyz", "end_effector_rpy_deg", "end_effectors")
_FRAME_GOAL_KEYS = ("xyz", "rpy_deg")
_PATH_KEYS = ("extra", "max_deviation_deg", "allow_full_turns", "objective", "raise_freedom")


def default_scenario_path() -> Path:
    """The shipped worked example of docs/method.md section 8."""
    return robots_dir() / "scenarios" / "worked_example.toml"


_check_keys = check_keys
_scenario_errors = scenario_errors
_number = number
_numbers = numbers
_triple = triple


@dataclass(frozen=True)
class Scenario:
    """A planning request, in radians and metres.

    Attributes:
        robot: the loaded free-floating robot.
        duration: motion time T (s).
        start_joints: ``{joint: value}`` at t = 0 (rad, or m for prismatic joints).
        goal_joints: ``{joint: value}`` at t = T (rad or m).
        start_attitude: base attitude at t = 0, quaternion ``[x, y, z, w]``.
        goal_attitude: wanted base attitude at t = T, quaternion ``[x, y, z, w]``.
        extra: free coefficients per joint beyond the quintic; None lets the planner choose.
        max_deviation: one-unknown root bracket as largest path deviation (rad); None: default.
        allow_full_turns: a continuous joint may reach its goal the other way round.
        objective: which path is best among those that reach the goal (a name of
            :data:`~freefloat.problem.objectives.OBJECTIVES`); default the paper's minimum norm.
        raise_freedom: an objective other than ``min_norm`` may add free coefficients beyond
            ``extra`` while it keeps falling (docs/method.md section 13).
        source: the TOML file it came from, if any.
        goal_poses: Cartesian goals per end-effector frame still to be solved for goal joints
            (by :meth:`resolved`); empty when the goal joints are given. With them,
            ``goal_joints`` holds the joint goals given (held while solving); the joints that
            move no goal frame and have no goal keep their start value.
        robot_text: the URDF of an inline servicer not yet written to ``robot.urdf`` (by
            :meth:`write_robot`); None otherwise.
        safety: what the plan must keep clear of (``[safety]``, ``[[obstacles]]``).
        payload: a captured payload held by the end effector (``[payload]``), if any.
        servicer: the description of an inline ``[robot]`` servicer, if the robot is one.
        srdf_text: the SRDF of a servicer of several arms not yet written to ``safety.srdf``
            (by :meth:`write_robot`); None otherwise.
        constraints: constraints beyond the defaults (``[constraints.<name>]`` tables).

    Reading a scenario is pure: no file is written and no inverse kinematics runs until
    :meth:`resolved` and :meth:`write_robot` are called (planning calls both).
    """

    robot: Robot
    duration: float
    start_joints: Mapping[str, float]
    goal_joints: Mapping[str, float]
    start_attitude: np.ndarray = field(default_factory=lambda: quat_from_zyx(0.0))
    goal_attitude: np.ndarray = field(default_factory=lambda: quat_from_zyx(0.0))
    extra: Mapping[str, int] | None = None
    max_deviation: float | None = None
    allow_full_turns: bool = False
    objective: str = DEFAULT_OBJECTIVE
    raise_freedom: bool = True
    source: Path | None = None
    goal_poses: Mapping[str, CartesianGoal] = field(default_factory=dict)
    robot_text: str | None = None
    safety: Safety = field(default_factory=lambda: Safety())
    payload: Payload | None = None
    servicer: ServicerSpec | None = None
    srdf_text: str | None = None
    constraints: tuple[Constraint, ...] = ()

    @property
    def goal_pose(self) -> CartesianGoal | None:
        """The first end effector's Cartesian goal still to be solved, if any."""
        return self.goal_poses.get(self.robot.end_effector)

    @classmethod
    def from_toml(cls, path: str | Path) -> Scenario:
        """Read a scenario file (degrees at this edge; see the module docstring).

        Raises:
            ScenarioError: unreadable file, bad TOML, or a bad value.
            UnknownNameError: an unknown key, joint or frame name (lists the valid ones).
            ModelError: the robot's URDF cannot be loaded.
        """
        path = absolute_path(path, "scenario", ScenarioError)
        data = read_toml(path, "scenario")
        try:
            return cls.from_dict(data, relative_to=path.parent, source=path)
        except FreeFloatError as exc:
            if str(path) in str(exc):
                raise
            raise _prefixed(exc, path) from None

    @classmethod
    def from_dict(
        cls,
        data: Mapping[str, Any],
        relative_to: Path | None = None,
        source: Path | None = None,
        known: Robot | None = None,
    ) -> Scenario:
        """Build a scenario from the parsed TOML tables (degrees; see the module docstring).

        ``known`` is a robot already loaded (a sweep's worker keeps one): it is used when it
        is the robot the tables name (the same URDF path, composed servicer or payload) and
        its end effector is the one asked for, instead of loading it again.
        """
        _check_keys(data, _TOP_KEYS, "the scenario")
        for key in ("robot", "duration", "start", "goal"):
            if key not in data:
                raise ScenarioError(
                    f"missing required key {key!r} (required: robot, duration, [start], [goal])"
                )
        origin = robot_source(data["robot"], data["start"], relative_to)
        urdf, robot_text, servicer = origin.urdf, origin.text, origin.servicer
        duration = _scenario_errors(check_duration, data["duration"])
        names = _end_effector_names(data, origin)
        payload = _payload(data.get("payload"))
        if payload is not None:
            first = names[0] if names else None
            urdf, robot_text = _with_payload(urdf, robot_text, first, payload)
        same = known is not None and known.urdf == Path(urdf).expanduser().resolve()
        if same and known is not None and (not names or names == known.end_effectors):
            robot = known
        else:
            robot = load_robot(urdf, names or None, text=robot_text)
        check_joint_count(robot.n, repr(robot.name))
        safety = _safety(data.get("safety"), data.get("obstacles"), relative_to)
        if safety.srdf is None and origin.srdf is not None:
            safety = replace(safety, srdf=origin.srdf)

        states: list[tuple[dict[str, float], np.ndarray]] = []
        goal_poses: dict[str, CartesianGoal] = {}
        for name in ("start", "goal"):
            table = data[name]
            if not isinstance(table, Mapping):
                raise ScenarioError(f"[{name}] must be a table")
            _check_keys(table, _GOAL_KEYS if name == "goal" else _STATE_KEYS, f"[{name}]")
            if "base_zyx_deg" in table and "base_quaternion_xyzw" in table:
                raise ScenarioError(
                    f"[{name}] gives both base_zyx_deg and base_quaternion_xyzw; give one"
                )
            if "base_quaternion_xyzw" in table:
                quat = _numbers(table["base_quaternion_xyzw"], 4, f"[{name}] base_quaternion_xyzw")
                if np.linalg.norm(quat) < 1e-9:
                    raise ScenarioError(f"[{name}] base_quaternion_xyzw must be non-zero")
                quat = quat / np.linalg.norm(quat)
            else:
                zyx = _numbers(
                    table.get("base_zyx_deg", [0.0, 0.0, 0.0]),
                    3,
                    f"[{name}] base_zyx_deg",
                    MAX_ANGLE_DEG,
                    "deg",
                )
                quat = quat_from_zyx(*np.radians(zyx))
            if name == "goal" and "end_effector_xyz" in table:
                if "joints" in table or "end_effectors" in table:
                    other = "joints" if "joints" in table else "end_effectors"
                    raise ScenarioError(f"[goal] gives both {other} and end_effector_xyz; give one")
                goal_poses = {robot.end_effector: _cartesian_goal(table)}
                joints = {}
            elif name == "goal" and "end_effectors" in table:
                goal_poses = _frame_goals(table["end_effectors"])
                joints = _joint_table(robot, table, name, origin.locked, partial=True)
            else:
                joints = _joint_table(robot, table, name, origin.locked)
            states.append((joints, quat))

        path_table = data.get("path", {})
        if not isinstance(path_table, Mapping):
            raise ScenarioError("[path] must be a table")
        _check_keys(path_table, _PATH_KEYS, "[path]")
        extra = None
        if "extra" in path_table:
            if not isinstance(path_table["extra"], Mapping):
                raise ScenarioError("[path] extra must be a table { joint = count, ... }")
            extra = {}
            for joint_name, count in path_table["extra"].items():
                robot.joint(joint_name)
                extra[joint_name] = _scenario_errors(
                    check_extra, count, f"[path] extra for {joint_name!r}"
                )
        max_deviation = None
        if "max_deviation_deg" in path_table:
            value = _number(
                path_table["max_deviation_deg"], "[path] max_deviation_deg", MAX_ANGLE_DEG, "deg"
            )
            if value <= 0.0:
                raise ScenarioError(f"[path] max_deviation_deg must be > 0, got {value:g}")
            max_deviation = math.radians(value)

        allow_full_turns = path_table.get("allow_full_turns", False)
        if not isinstance(allow_full_turns, bool):
            raise ScenarioError(
                f"[path] allow_full_turns must be true or false, got {excerpt(allow_full_turns)}"
            )
        objective = path_table.get("objective", DEFAULT_OBJECTIVE)
        if not isinstance(objective, str) or objective not in OBJECTIVES:
            raise ScenarioError(
                f"[path] objective must be one of {', '.join(OBJECTIVES)}, got {excerpt(objective)}"
            )
        raise_freedom = path_table.get("raise_freedom", True)
        if not isinstance(raise_freedom, bool):
            raise ScenarioError(
                f"[path] raise_freedom must be true or false, got {excerpt(raise_freedom)}"
            )
        return cls(
            robot=robot,
            allow_full_turns=allow_full_turns,
            objective=objective,
            raise_freedom=raise_freedom,
            duration=duration,
            start_joints=states[0][0],
            goal_joints=states[1][0],
            start_attitude=states[0][1],
            goal_attitude=states[1][1],
            extra=extra,
            max_deviation=max_deviation,
            source=source,
            goal_poses=goal_poses,
            robot_text=robot_text,
            safety=safety,
            payload=payload,
            servicer=servicer,
            srdf_text=origin.srdf_text,
            constraints=_constraints(data.get("constraints", {})),
        )

    def resolved(self) -> Scenario:
        """This scenario with its Cartesian goal solved into goal joints (a copy; or itself).

        Raises:
            UnreachableGoalError: no configuration reaches the end-effector goal.
        """
        if not self.goal_poses:
            return self
        from ..physics.momentum import MomentumMap
        from .cartesian import FrameGoal, solve_frame_goals

        goals = [FrameGoal(f, g.position, g.rotation) for f, g in self.goal_poses.items()]
        values = solve_frame_goals(
            MomentumMap(self.robot), goals, self.goal_attitude, self.start, self.goal_joints
        )
        joints = dict(zip(self.robot.joint_names, values.tolist(), strict=True))
        return replace(self, goal_joints=joints, goal_poses={})

    def write_robot(self) -> Path:
        """Write an inline servicer's URDF (and SRDF) to its cache file if not there; return it."""
        srdf = self.safety.srdf
        if self.srdf_text is not None and srdf is not None and not srdf.is_file():
            atomic_write_text(srdf, self.srdf_text)
        path = self.robot.urdf
        if self.robot_text is not None and not path.is_file():
            atomic_write_text(path, self.robot_text)
        return path

    @property
    def start(self) -> np.ndarray:
        """Start joint values as an N-vector in joint order (rad or m)."""
        return self.robot.vector(self.start_joints, "start joints")

    @property
    def goal(self) -> np.ndarray:
        """Goal joint values as an N-vector in joint order (rad or m).

        A Cartesian goal is solved here each time it is asked for; :meth:`resolved` solves it
        once.
        """
        if self.goal_poses:
            return self.resolved().goal
        return self.robot.vector(self.goal_joints, "goal joints")


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
        raise ScenarioError(f"{path}: invalid TOML ({excerpt(str(exc), 200)[1:-1]})") from None
    except RecursionError:
        raise ScenarioError(
            f"{path}: arrays or tables nested too deeply for freefloat to read"
        ) from None
    except ValueError as exc:  # an integer of more digits than Python converts
        raise ScenarioError(f"{path}: invalid TOML ({excerpt(str(exc), 200)[1:-1]})") from None


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
    for joint_name, value in raw.items():
        if joint_name in locked:
            _check_locked(joint_name, value, locked[joint_name], name)
            continue
        joint = robot.joint(joint_name)
        limit, unit = (MAX_ANGLE_DEG, "deg") if joint.angular else (MAX_LENGTH_M, "m")
        number = _number(value, f"[{name}] joint {joint_name!r}", limit, unit)
        joints[joint_name] = math.radians(number) if joint.angular else number
    if not partial:
        robot.vector(joints, f"[{name}] joints")  # every joint given
    return joints


def _check_locked(joint: str, value: Any, locked: float, where: str) -> None:
    """A locked joint named in ``[start]`` or ``[goal]`` must be at its locked value."""
    given = _number(value, f"[{where}] joint {joint!r}", MAX_ANGLE_DEG)
    for amount, _unit in ((math.degrees(locked), "deg"), (locked, "m")):
        if abs(given - amount) <= 1e-9 * max(1.0, abs(amount)):
            return
    raise ScenarioError(
        f"[{where}] joint {joint!r} is {given:g} but the joint is locked at "
        f"{math.degrees(locked):.6g} deg (m for a prismatic joint); give that value or leave "
        "it out"
    )


def _end_effector_names(data: Mapping[str, Any], source: RobotSource) -> tuple[str, ...]:
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
        _check_keys(table, _FRAME_GOAL_KEYS, where)
        goals[str(frame)] = _pose(table["xyz"], table.get("rpy_deg"), where)
    return goals


@dataclass(frozen=True)
class CartesianGoal:
    """An end-effector goal, from the system CM in the inertial frame.

    Attributes:
        position: wanted end-effector position (m).
        rotation: wanted end-effector orientation (3 x 3), or None for position only.
    """

    position: np.ndarray
    rotation: np.ndarray | None = None


def _cartesian_goal(table: Mapping[str, Any]) -> CartesianGoal:
    """The Cartesian goal of ``end_effector_xyz`` (m) and optional ``end_effector_rpy_deg``."""
    return _pose(
        table["end_effector_xyz"], table.get("end_effector_rpy_deg"), "[goal] end_effector"
    )


def _pose(xyz_value: Any, rpy_value: Any, where: str) -> CartesianGoal:
    """A goal from ``xyz`` (m, from the system CM) and roll, pitch, yaw (deg) or None."""
    suffix = "_" if where.endswith("end_effector") else " "
    xyz = _numbers(xyz_value, 3, f"{where}{suffix}xyz", MAX_LENGTH_M, "m")
    rotation = None
    if rpy_value is not None:
        rpy = _numbers(rpy_value, 3, f"{where}{suffix}rpy_deg", MAX_ANGLE_DEG, "deg")
        rpy = np.radians(rpy)
        rotation = quat_to_matrix(quat_from_zyx(rpy[2], rpy[1], rpy[0]))
    return CartesianGoal(xyz, rotation)


@dataclass(frozen=True)
class Safety:
    """What the plan must keep clear of.

    Attributes:
        margin: required clearance between checked bodies (m).
        srdf: SRDF whose disabled pairs are not checked; None: the known SRDF of a composed
            example-robot-data arm, or none.
        obstacles: keep-out objects fixed to the spacecraft.
        check: whether clearance is a constraint at all (``[safety] check = false`` turns it
            off; verification then reports no clearance check).
    """

    margin: float = 0.01
    srdf: Path | None = None
    obstacles: tuple[Obstacle, ...] = ()
    check: bool = True


def _safety(table: Any, obstacles: Any, relative_to: Path | None) -> Safety:
    """``[safety]`` and ``[[obstacles]]`` (metres, degrees) as a :class:`Safety`."""
    table = {} if table is None else table
    if not isinstance(table, Mapping):
        raise ScenarioError("[safety] must be a table")
    _check_keys(table, _SAFETY_KEYS, "[safety]")
    margin = _number(table.get("margin_m", 0.01), "[safety] margin_m", MAX_LENGTH_M, "m")
    if margin < 0.0:
        raise ScenarioError(f"[safety] margin_m must be >= 0 m, got {margin:g}")
    srdf = None
    if "srdf" in table:
        if not isinstance(table["srdf"], str):
            raise ScenarioError(f"[safety] srdf must be a file path, got {excerpt(table['srdf'])}")
        srdf = Path(table["srdf"]).expanduser()
        if not srdf.is_absolute() and relative_to is not None:
            srdf = relative_to / srdf
        if not srdf.is_file():
            raise ScenarioError(f"[safety] srdf file not found: {srdf}")
    check = table.get("check", True)
    if not isinstance(check, bool):
        raise ScenarioError(f"[safety] check must be true or false, got {excerpt(check)}")
    items = [] if obstacles is None else obstacles
    if not isinstance(items, list) or not all(isinstance(o, Mapping) for o in items):
        raise ScenarioError("[[obstacles]] must be a list of tables")
    parsed = []
    for index, item in enumerate(items):
        where = f"[[obstacles]] #{index + 1}"
        _check_keys(item, _OBSTACLE_KEYS, where)
        name = item.get("name", f"obstacle_{index + 1}")
        if not isinstance(name, str) or not name:
            raise ScenarioError(f"{where}: name must be a non-empty string")
        shapes = [s for s in ("box", "sphere", "capsule") if s in item]
        if len(shapes) != 1:
            raise ScenarioError(
                f"{where} ({name}): give exactly one shape: box = [x, y, z], sphere = r or "
                "capsule = [r, length] (m)"
            )
        shape = shapes[0]
        raw = item[shape]
        if shape == "sphere":
            size = (_number(raw, f"{where} sphere", MAX_LENGTH_M, "m"),)
        else:
            count = 3 if shape == "box" else 2
            size = tuple(_numbers(raw, count, f"{where} {shape}", MAX_LENGTH_M, "m"))
        try:
            parsed.append(
                Obstacle(
                    name,
                    shape,
                    tuple(float(s) for s in size),
                    _triple(item, "xyz", [0.0, 0.0, 0.0], where),
                    _radians3(_triple(item, "rpy_deg", [0.0] * 3, where)),
                )
            )
        except InputError as exc:
            raise ScenarioError(str(exc)) from None
    names = [o.name for o in parsed]
    if len(set(names)) != len(names):
        raise ScenarioError(f"[[obstacles]] names must be unique, got {excerpt(names)}")
    return Safety(margin, srdf, tuple(parsed), check)


def _constraints(table: Any) -> tuple[Constraint, ...]:
    """``[constraints.<name>]`` tables as constraints, by the registry."""
    if not isinstance(table, Mapping):
        raise ScenarioError("[constraints] must hold one table per constraint, by name")
    out = []
    always = [c.name for c in default_constraints()]
    for name, parameters in table.items():
        if name in always:
            raise ScenarioError(f"[constraints.{name}]: always honoured, it takes no table")
        try:
            out.append(constraint_from_record(name, parameters))
        except UnknownNameError:
            raise
        except InputError as exc:
            raise ScenarioError(f"[constraints.{name}] {exc}") from None
    return tuple(out)


def _radians3(degrees: tuple[float, float, float]) -> tuple[float, float, float]:
    return (math.radians(degrees[0]), math.radians(degrees[1]), math.radians(degrees[2]))


def _payload(table: Any) -> Payload | None:
    """``[payload]`` (kg, m, kg m^2) as a :class:`Payload`, or None."""
    if table is None:
        return None
    if not isinstance(table, Mapping):
        raise ScenarioError("[payload] must be a table")
    _check_keys(table, _PAYLOAD_KEYS, "[payload]")
    if "mass" not in table or "inertia" not in table:
        raise ScenarioError(
            "[payload] needs mass [kg] and inertia = [ixx, iyy, izz, ixy, ixz, iyz]"
        )
    try:
        return Payload(
            mass=_number(table["mass"], "[payload] mass", MAX_MAGNITUDE, "kg"),
            com_xyz=_triple(table, "com_xyz", [0.0, 0.0, 0.0], "[payload]"),
            inertia=tuple(float(v) for v in _numbers(table["inertia"], 6, "[payload] inertia")),  # type: ignore[arg-type]
            box=_triple(table, "box", None, "[payload]") if "box" in table else None,
        )
    except InputError as exc:
        raise ScenarioError(str(exc)) from None


def _with_payload(
    urdf: Path, text: str | None, end_effector: str | None, payload: Payload
) -> tuple[Path, str]:
    """The cache path and text of the robot's URDF with the payload attached."""
    if text is None:
        text = read_text_file(urdf, "URDF", MAX_URDF_BYTES, ScenarioError)
    link = end_effector or load_robot(urdf, None, text=text).end_effector
    decorated = attach_payload(text, link, payload, Path(urdf).resolve().parent)
    digest = hashlib.sha256(decorated.encode()).hexdigest()[:16]
    return servicer_cache_dir() / f"{Path(urdf).stem}-payload-{digest}.urdf", decorated


def _prefixed(exc: FreeFloatError, path: Path) -> FreeFloatError:
    """The same error with the scenario file named in front of its message."""
    exc.args = (f"{path}: {exc}",)
    return exc

"""Scenarios: what to plan, read from a TOML file.

The file speaks degrees (joint angles, Euler angles) and metres (prismatic joints); a
:class:`Scenario` holds radians and metres. Format::

    robot = "planar_2dof"          # a shipped robot name, a URDF path relative to this file,
                                   # or a [robot] table composing a servicer (see below)
    duration = 10.0                # [s]
    end_effector = "ee"            # optional frame name; default: the tip of the chain
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
"""

from __future__ import annotations

import hashlib
import math
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import (
    FreeFloatError,
    InputError,
    InputLimitError,
    ScenarioError,
    UnknownNameError,
    excerpt,
)
from ..files import absolute_path, atomic_write_text, read_text_file
from ..physics.attitude import quat_from_zyx, quat_to_matrix
from ..robot.collision import Obstacle
from ..robot.model import MAX_URDF_BYTES, Robot, load_robot, resolve_robot, robots_dir
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
    check_number,
)
from .objectives.registry import DEFAULT_OBJECTIVE, OBJECTIVES

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
_GOAL_KEYS = (*_STATE_KEYS, "end_effector_xyz", "end_effector_rpy_deg")
_PATH_KEYS = ("extra", "max_deviation_deg", "allow_full_turns", "objective", "raise_freedom")


def default_scenario_path() -> Path:
    """The shipped worked example of docs/method.md section 8."""
    return robots_dir() / "scenarios" / "worked_example.toml"


def _check_keys(table: Mapping[str, Any], valid: tuple[str, ...], where: str) -> None:
    for key in table:
        if key not in valid:
            raise UnknownNameError(f"key in {where}", key, valid)


def _scenario_errors(check: Any, *args: Any, **kwargs: Any) -> Any:
    """``check(*args, **kwargs)`` with its plain input errors as :class:`ScenarioError`.

    Limit errors (:class:`InputLimitError`) pass as they are: they carry the limit.
    """
    try:
        return check(*args, **kwargs)
    except InputLimitError:
        raise
    except InputError as exc:
        raise ScenarioError(str(exc)) from None


def _number(value: Any, where: str, limit: float = MAX_MAGNITUDE, unit: str = "") -> float:
    """A finite number of magnitude at most ``limit`` (docs/limits.md)."""
    return float(_scenario_errors(check_number, value, where, limit, unit))


def _numbers(
    value: Any, count: int, where: str, limit: float = MAX_MAGNITUDE, unit: str = ""
) -> np.ndarray:
    if not isinstance(value, list) or len(value) != count:
        raise ScenarioError(f"{where} must be a list of {count} numbers, got {excerpt(value)}")
    return np.array([_number(v, f"{where}[{i}]", limit, unit) for i, v in enumerate(value)])


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
        goal_pose: a Cartesian end-effector goal still to be solved for goal joints (by
            :meth:`resolved`); None when the goal joints are given.
        robot_text: the URDF of an inline servicer not yet written to ``robot.urdf`` (by
            :meth:`write_robot`); None otherwise.
        safety: what the plan must keep clear of (``[safety]``, ``[[obstacles]]``).
        payload: a captured payload held by the end effector (``[payload]``), if any.
        servicer: the description of an inline ``[robot]`` servicer, if the robot is one.
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
    goal_pose: CartesianGoal | None = None
    robot_text: str | None = None
    safety: Safety = field(default_factory=lambda: Safety())
    payload: Payload | None = None
    servicer: ServicerSpec | None = None
    constraints: tuple[Constraint, ...] = ()

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
        robot_text, servicer = None, None
        if isinstance(data["robot"], Mapping):
            urdf, robot_text, servicer = _inline_servicer(data["robot"])
        elif isinstance(data["robot"], str):
            urdf = resolve_robot(data["robot"], relative_to)
        else:
            raise ScenarioError(
                "robot must be a shipped robot name, a URDF path or a [robot] table, got "
                f"{excerpt(data['robot'])}"
            )
        duration = _scenario_errors(check_duration, data["duration"])
        end_effector = data.get("end_effector")
        if end_effector is not None and not isinstance(end_effector, str):
            raise ScenarioError(f"end_effector must be a frame name, got {excerpt(end_effector)}")
        payload = _payload(data.get("payload"))
        if payload is not None:
            urdf, robot_text = _with_payload(urdf, robot_text, end_effector, payload)
        same = known is not None and known.urdf == Path(urdf).expanduser().resolve()
        if same and known is not None and end_effector in (None, known.end_effector):
            robot = known
        else:
            robot = load_robot(urdf, end_effector, text=robot_text)
        check_joint_count(robot.n, repr(robot.name))
        safety = _safety(data.get("safety"), data.get("obstacles"), relative_to)

        states: list[tuple[dict[str, float], np.ndarray]] = []
        goal_pose = None
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
                if "joints" in table:
                    raise ScenarioError("[goal] gives both joints and end_effector_xyz; give one")
                goal_pose = _cartesian_goal(table)
                joints = {}
            else:
                joints = _joint_table(robot, table, name)
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
            goal_pose=goal_pose,
            robot_text=robot_text,
            safety=safety,
            payload=payload,
            servicer=servicer,
            constraints=_constraints(data.get("constraints", {})),
        )

    def resolved(self) -> Scenario:
        """This scenario with its Cartesian goal solved into goal joints (a copy; or itself).

        Raises:
            UnreachableGoalError: no configuration reaches the end-effector goal.
        """
        if self.goal_pose is None:
            return self
        from ..physics.momentum import MomentumMap
        from .cartesian import solve_cartesian_goal

        values = solve_cartesian_goal(
            MomentumMap(self.robot),
            self.goal_pose.position,
            self.goal_attitude,
            self.start,
            self.goal_pose.rotation,
        )
        joints = dict(zip(self.robot.joint_names, values.tolist(), strict=True))
        return replace(self, goal_joints=joints, goal_pose=None)

    def write_robot(self) -> Path:
        """Write an inline servicer's URDF to its cache file if it is not there; return it."""
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
        if self.goal_pose is not None:
            return self.resolved().goal
        return self.robot.vector(self.goal_joints, "goal joints")


_ROBOT_KEYS = (
    "arm",
    "base_mass",
    "base_size",
    "base_inertia",
    "mount",
    "mount_rpy_deg",
    "lock",
    "keep_gripper",
)


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


def servicer_cache_dir() -> Path:
    """Folder of servicers composed from inline ``[robot]`` tables.

    ``$FREEFLOAT_CACHE`` if set, else ``$XDG_CACHE_HOME/freefloat/servicers`` (default
    ``~/.cache``).
    """
    if os.environ.get("FREEFLOAT_CACHE"):
        return Path(os.environ["FREEFLOAT_CACHE"])
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "freefloat" / "servicers"


def _triple(
    table: Mapping[str, Any],
    key: str,
    default: list[float] | None = None,
    where: str = "[robot]",
) -> Any:
    limit, unit = (MAX_ANGLE_DEG, "deg") if key.endswith("_deg") else (MAX_LENGTH_M, "m")
    if key.endswith("inertia"):
        limit, unit = MAX_MAGNITUDE, "kg m^2"
    values = _numbers(table.get(key, default), 3, f"{where} {key}", limit, unit)
    return tuple(float(x) for x in values)


def _inline_servicer(table: Mapping[str, Any]) -> tuple[Path, str | None, ServicerSpec]:
    """The cache path of the servicer an inline ``[robot]`` table describes, and its URDF.

    The URDF text is None when the cache file exists (it is read from there); otherwise the
    servicer is composed in memory and written only by :meth:`Scenario.write_robot`.
    """
    from ..robot.compose import ServicerSpec, compose_servicer_text

    _check_keys(table, _ROBOT_KEYS, "[robot]")
    for key in ("arm", "base_mass", "base_size"):
        if key not in table:
            raise ScenarioError(f"[robot] needs {key!r} (required: arm, base_mass, base_size)")
    if not isinstance(table["arm"], str):
        raise ScenarioError(
            f"[robot] arm must be an arm name or a URDF path, got {excerpt(table['arm'])}"
        )
    lock = table.get("lock", [])
    if not isinstance(lock, list) or not all(isinstance(x, str) for x in lock):
        raise ScenarioError("[robot] lock must be a list of joint names")
    spec = ServicerSpec(
        arm=table["arm"],
        base_mass=_number(table["base_mass"], "[robot] base_mass", MAX_MAGNITUDE, "kg"),
        base_size=_triple(table, "base_size"),
        base_inertia=_triple(table, "base_inertia") if "base_inertia" in table else None,
        mount=_triple(table, "mount", [0.0, 0.0, 0.0]),
        mount_rpy=tuple(math.radians(a) for a in _triple(table, "mount_rpy_deg", [0.0] * 3)),
        lock=tuple(lock),
        keep_gripper=bool(table.get("keep_gripper", False)),
    )
    path = servicer_cache_dir() / f"{spec.key()}.urdf"
    if path.is_file():
        return path, None, spec
    return path, compose_servicer_text(spec), spec


def _joint_table(robot: Robot, table: Mapping[str, Any], name: str) -> dict[str, float]:
    """``{joint: value}`` in rad or m from a ``joints`` table in degrees (m for prismatic)."""
    if "joints" not in table or not isinstance(table["joints"], Mapping):
        extra = " (or end_effector_xyz = [x, y, z])" if name == "goal" else ""
        raise ScenarioError(
            f"[{name}] needs joints = {{ name = value, ... }}{extra} "
            f"(joints: {', '.join(robot.joint_names)})"
        )
    joints: dict[str, float] = {}
    for joint_name, value in table["joints"].items():
        joint = robot.joint(joint_name)
        limit, unit = (MAX_ANGLE_DEG, "deg") if joint.angular else (MAX_LENGTH_M, "m")
        number = _number(value, f"[{name}] joint {joint_name!r}", limit, unit)
        joints[joint_name] = math.radians(number) if joint.angular else number
    robot.vector(joints, f"[{name}] joints")  # every joint given
    return joints


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
    xyz = _numbers(table["end_effector_xyz"], 3, "[goal] end_effector_xyz", MAX_LENGTH_M, "m")
    rotation = None
    if "end_effector_rpy_deg" in table:
        where = "[goal] end_effector_rpy_deg"
        rpy = np.radians(_numbers(table["end_effector_rpy_deg"], 3, where, MAX_ANGLE_DEG, "deg"))
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

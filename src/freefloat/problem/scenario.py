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
    [payload]                      # rigidly held by an end effector
    held_by = "tool0"              # optional: which one (default: the scenario's first)
    mass = 300.0                   # [kg]
    com_xyz = [0.0, 0.0, 0.4]      # its CM in the end-effector frame [m]
    inertia = [20.0, 20.0, 20.0, 0.0, 0.0, 0.0]   # about that CM [kg m^2]
    box = [0.6, 0.6, 0.6]          # optional collision shape centred on the CM [m]; without
                                   # inertia, a uniform box's

An inline servicer replaces ``robot = "..."`` with a table (composed in memory when read;
written to its content-addressed cache file when a plan is made, see :meth:`Scenario.write_robot`)::

    [robot]
    arm = "panda"                  # example-robot-data arm or URDF path
    base_mass = 100.0              # [kg]
    base_size = [0.6, 0.6, 0.6]    # [m]
    mount = [0.3, 0.0, 0.0]        # [m], in the spacecraft frame
    mount_rpy_deg = [0.0, 90.0, 0.0]   # optional [deg]; also base_inertia, lock, keep_gripper

Reading is pure parsing (:mod:`freefloat.problem.scenario_tables`,
:mod:`freefloat.problem.scenario_safety`, :mod:`freefloat.problem.robot_table`); resolution is
explicit: :meth:`Scenario.resolved` solves Cartesian goals by inverse kinematics and
:meth:`Scenario.write_robot` writes a composed robot to its cache file.

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
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import FreeFloatError, InputError, ScenarioError
from ..files import absolute_path, read_text_file
from ..physics.attitude import quat_from_zyx
from ..robot.model import MAX_URDF_BYTES, Robot, load_robot, robots_dir
from ..robot.payload import Payload, attach_payload
from .cache_files import write_cached
from .constraints.base import Constraint
from .limits import check_duration, check_joint_count
from .objectives.registry import DEFAULT_OBJECTIVE
from .payload_table import payload_holder, payload_table
from .robot_table import robot_source, scenario_errors, servicer_cache_dir
from .scenario_safety import Safety, constraint_tables, safety_tables
from .scenario_tables import (
    CartesianGoal,
    check_top_keys,
    end_effector_names,
    path_options,
    read_toml,
    state_tables,
)

if TYPE_CHECKING:
    from ..robot.compose import ServicerSpec

__all__ = [
    "Scenario",
    "default_scenario_path",
    "scenario_of",
    "shipped_scenario",
    "shipped_scenario_names",
]


def default_scenario_path() -> Path:
    """The shipped worked example of docs/method.md section 8."""
    return robots_dir() / "scenarios" / "worked_example.toml"


def shipped_scenario(name: str) -> Path | None:
    """The shipped scenario called ``name`` (``panda_servicer`` or ``panda_servicer.toml``).

    None when no shipped scenario has that name (a path with a folder in it never does).
    """
    if Path(name).name != name:
        return None
    folder = robots_dir() / "scenarios"
    try:
        found = next((p for p in (folder / name, folder / f"{name}.toml") if p.is_file()), None)
    except OSError:  # a name too long for the file system is no shipped scenario's
        return None
    return None if found is None else found.resolve()


def shipped_scenario_names() -> list[str]:
    """The shipped scenarios' names, sorted (``panda_servicer``...)."""
    return sorted(p.stem for p in (robots_dir() / "scenarios").glob("*.toml"))


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
            raise exc.naming(path) from None

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
        check_top_keys(data)
        origin = robot_source(data["robot"], data["start"], relative_to)
        urdf, robot_text = origin.urdf, origin.text
        duration = scenario_errors(check_duration, data["duration"])
        names = end_effector_names(data, origin)
        payload = payload_table(data.get("payload"))
        if payload is not None:
            held_by = data["payload"].get("held_by")
            holder = payload_holder(held_by, names) if names else None
            urdf, robot_text = _with_payload(urdf, robot_text, holder, payload, held_by)
        same = known is not None and known.urdf == Path(urdf).expanduser().resolve()
        if same and known is not None and (not names or names == known.end_effectors):
            robot = known
        else:
            robot = load_robot(urdf, names or None, text=robot_text)
        check_joint_count(robot.n, repr(robot.name))
        safety = safety_tables(data.get("safety"), data.get("obstacles"), relative_to)
        if safety.srdf is None and origin.srdf is not None:
            safety = replace(safety, srdf=origin.srdf)
        states = state_tables(data, robot, origin.locked)
        path = path_options(data.get("path", {}), robot, origin.locked)
        return cls(
            robot=robot,
            allow_full_turns=path.allow_full_turns,
            objective=path.objective,
            raise_freedom=path.raise_freedom,
            duration=duration,
            start_joints=states.start_joints,
            goal_joints=states.goal_joints,
            start_attitude=states.start_attitude,
            goal_attitude=states.goal_attitude,
            extra=path.extra,
            max_deviation=path.max_deviation,
            source=source,
            goal_poses=states.goal_poses,
            robot_text=robot_text,
            safety=safety,
            payload=payload,
            servicer=origin.servicer,
            srdf_text=origin.srdf_text,
            constraints=constraint_tables(data.get("constraints", {})),
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
        """Write a composed robot's URDF (and SRDF) to its cache file unless there; return it.

        A cache file is rewritten when its digest does not vouch for it
        (:mod:`.cache_files`).
        """
        srdf = self.safety.srdf
        if self.srdf_text is not None and srdf is not None:
            write_cached(srdf, self.srdf_text)
        path = self.robot.urdf
        if self.robot_text is not None:
            write_cached(path, self.robot_text)
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


def _with_payload(
    urdf: Path, text: str | None, end_effector: str | None, payload: Payload, held_by: Any
) -> tuple[Path, str]:
    """The cache path and text of the robot's URDF with the payload attached.

    ``end_effector``: the holder the scenario's end effectors decided; None when it lists
    none: then ``held_by`` (the table's value) must name one of the robot's own.
    """
    if text is None:
        text = read_text_file(urdf, "URDF", MAX_URDF_BYTES, ScenarioError)
    if end_effector is None:  # the robot's default end effector, or one of them
        defaults = load_robot(urdf, None, text=text).end_effectors
        end_effector = payload_holder(held_by, tuple(defaults)) or defaults[0]
    decorated = attach_payload(text, end_effector, payload, Path(urdf).resolve().parent)
    digest = hashlib.sha256(decorated.encode()).hexdigest()[:16]
    return servicer_cache_dir() / f"{Path(urdf).stem}-payload-{digest}.urdf", decorated


def scenario_of(scenario: Scenario | str | os.PathLike) -> Scenario:
    """``scenario`` itself, or the scenario file it names read (:meth:`Scenario.from_toml`).

    Raises:
        InputError: neither a :class:`Scenario` nor a path.
        ScenarioError, UnknownNameError, ModelError: as :meth:`Scenario.from_toml`.
    """
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, (str, os.PathLike)):
        return Scenario.from_toml(Path(scenario))
    raise InputError(
        f"scenario must be a freefloat.Scenario or the path of a scenario TOML file, got "
        f"{type(scenario).__name__}"
    )

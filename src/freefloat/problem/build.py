"""Building a planning problem: checks, freedom, planar branch (docs/method.md sections 4-6).

:func:`build_problem` turns joint values and attitudes into a :class:`Problem`;
:func:`problem_from_scenario` is the one way from a :class:`Scenario` to a problem. Building
checks every input (finite numbers, a positive duration, unit quaternions, joints within their
limits), chooses the planar yaw branch inside the bounds, and picks the integration steps for
the quintic path. Nothing is solved here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from ..errors import InfeasibleError, InputError, JointLimitError
from ..physics.attitude import geodesic_angle, quat_exp, quat_multiply, relative_rotvec
from ..physics.momentum import MomentumMap, cached_planar_axis
from ..physics.planar_map import cached_identify
from ..robot.model import Robot
from .bounds import PlanarBounds, cached_planar_bounds
from .limits import check_duration, check_extra, check_joint_count
from .paths import PathFamily
from .residual import Problem, wrap_angle
from .scenario import Scenario

__all__ = ["build_problem", "check_joint_limits", "planar_yaw_branch", "problem_from_scenario"]


def planar_yaw_branch(yaw_change: float, lo: float, hi: float) -> float | None:
    """The branch ``yaw_change + 2 pi k`` inside the open interval ``(lo, hi)`` (rad).

    The one nearest zero when several are inside; None when none is. When no joint moves the
    interval shrinks to the single point 0, which then counts as inside.
    """
    branches = [yaw_change + 2.0 * math.pi * k for k in range(-3, 4)]
    inside = [b for b in branches if lo < b < hi or (lo == hi == 0.0 and b == 0.0)]
    return min(inside, key=abs) if inside else None


def _axis_name(axis: np.ndarray) -> str:
    for name, unit in (("z", (0, 0, 1)), ("y", (0, 1, 0)), ("x", (1, 0, 0))):
        if np.allclose(np.abs(axis), unit, atol=1e-12):
            return f"its {name} axis"
    return f"the axis {np.round(axis, 6).tolist()} of its frame"


def _check_finite(name: str, values: np.ndarray) -> None:
    if not np.all(np.isfinite(values)):
        raise InputError(f"{name} contains NaN or infinite values; give finite numbers")


def check_joint_limits(robot: Robot, values: np.ndarray, where: str) -> None:
    """Refuse joint values (rad or m) outside the URDF limits; ``where`` is start or goal.

    Raises:
        JointLimitError: the first joint outside its limits, named, in deg or m.
    """
    for joint, value in zip(robot.joints, values, strict=True):
        if joint.kind == "continuous":
            continue
        if not joint.lower - 1e-12 <= value <= joint.upper + 1e-12:
            scale = 180.0 / math.pi if joint.angular else 1.0
            unit = "deg" if joint.angular else "m"
            raise JointLimitError(joint.name, value, joint.lower, joint.upper, where, unit, scale)


def build_problem(
    robot: Robot,
    start: np.ndarray,
    goal: np.ndarray,
    start_quaternion: np.ndarray,
    goal_quaternion: np.ndarray,
    duration: float,
    extra: Sequence[int] | Mapping[str, int] | None = None,
    mmap: MomentumMap | None = None,
    check_bounds: bool = True,
) -> Problem:
    """Build and check a planning problem.

    Args:
        robot: the free-floating robot.
        start: N start joint values (rad or m).
        goal: N goal joint values (rad or m).
        start_quaternion: base attitude at t = 0, ``[x, y, z, w]``.
        goal_quaternion: wanted base attitude at t = T, ``[x, y, z, w]``.
        duration: motion time T (s), > 0.
        extra: free coefficients beyond the quintic per joint (a sequence of N counts or a
            ``{joint: count}`` mapping); default one on the joint nearest the base for planar
            systems and one on each of the first three joints otherwise.
        mmap: momentum-map evaluator to reuse.
        check_bounds: refuse planar requests outside the planar bounds (docs/method.md section 6).

    Raises:
        InputError: non-finite numbers, a non-positive duration, a bad quaternion.
        InputLimitError: a duration, a joint count or a count of free coefficients beyond
            freefloat's limits (:mod:`freefloat.problem.limits`).
        JointLimitError: start or goal outside the joint limits.
        InfeasibleError: planar request outside the reachable interval, or a goal attitude a
            planar system cannot reach (it only turns about its z axis).
    """
    start = np.asarray(start, dtype=float)
    goal = np.asarray(goal, dtype=float)
    quats = _checked_inputs(robot, start, goal, start_quaternion, goal_quaternion, duration)
    mmap = mmap or MomentumMap(robot)
    axis = cached_planar_axis(robot)
    planar = axis is not None
    planar_map = None
    if axis is not None:
        planar_map = cached_identify(robot)
    counts = _free_counts(robot, extra, planar)
    family = PathFamily.with_extra(start, goal, counts)

    bounds = yaw_change = None
    if axis is not None:
        yaw_change = _planar_yaw_change(quats, axis)
        bounds = cached_planar_bounds(mmap)
        lo, hi = bounds.interval(goal - start)
        # one joint: checked below, on the exact change; joints that end where they start
        # move only in loops, which no simple-motion bound covers (solvers/loop_start.py)
        if check_bounds and robot.n > 1 and not np.array_equal(start, goal):
            branch = planar_yaw_branch(yaw_change, lo, hi)
            if branch is None:
                interval = (math.degrees(lo), math.degrees(hi))
                raise InfeasibleError(math.degrees(yaw_change), interval)
            yaw_change = branch
    problem = Problem(
        robot=robot,
        mmap=mmap,
        family=family,
        duration=float(duration),
        start_quaternion=quats[0],
        goal_quaternion=quats[1],
        planar=planar,
        axis=np.array([0.0, 0.0, 1.0]) if axis is None else axis,
        planar_map=planar_map,
        bounds=bounds,
        yaw_change=yaw_change,
    )
    if family.n_free < problem.n_equations:
        raise InputError(
            f"{family.n_free} free path coefficient(s) for {problem.n_equations} attitude "
            f"equation(s); add at least {problem.n_equations - family.n_free} more with "
            "[path] extra (or leave extra out to let the planner choose)"
        )
    problem = problem.with_steps(problem.steps_for())
    return _one_joint(problem, check_bounds) if robot.n == 1 else problem


#: How far (rad) a one-joint robot's goal may lie from the one attitude it reaches before it
#: is refused here: verification's attitude tolerance, the loosest a plan can be asked for
#: (more when the integration's own error estimate is larger); a goal nearer is the solver's
#: to judge at the tolerance it was given.
ONE_JOINT_TOLERANCE = 1e-7


def _one_joint(problem: Problem, check_bounds: bool) -> Problem:
    """A one-joint problem: the goal held to the one attitude every path reaches.

    With one joint the base's attitude obeys an ODE in that joint's value alone (a path that
    goes back and forth retraces it), so every path reaches the quintic path's attitude
    (docs/method.md section 6): on the problem's own grid (chosen for it). A planar problem's
    bounds become that one change (their gain its mean over the travel). With
    ``check_bounds`` the goal is held to it, within :data:`ONE_JOINT_TOLERANCE` or the
    integration's own error estimate if larger, and a planar goal's branch taken. A new
    problem (residuals remembered for the old goal's branch are not carried over).

    Raises:
        InfeasibleError: the goal asks another attitude.
    """
    beta = np.zeros(problem.n_free)
    if not problem.planar:
        drift = problem.achieved(beta)
        off = geodesic_angle(drift, problem.goal_quaternion)
        tolerance = max(ONE_JOINT_TOLERANCE, problem.integration_error(beta))
        if check_bounds and off > tolerance:
            raise InfeasibleError(
                math.degrees(off), (0.0, 0.0), message=_one_attitude(drift, off, tolerance)
            )
        return problem
    exact = problem.yaw_change_of(beta)
    travel = float(problem.family.goal[0] - problem.family.start[0])
    gain = np.array([exact / travel if travel != 0.0 else 0.0])
    if not check_bounds or problem.yaw_change is None:
        return replace(problem, bounds=PlanarBounds(gain, gain))
    tolerance = max(ONE_JOINT_TOLERANCE, problem.integration_error(beta))
    off = wrap_angle(problem.yaw_change - exact)
    if abs(off) > tolerance:
        reached = quat_multiply(problem.start_quaternion, quat_exp(exact * problem.axis))
        raise InfeasibleError(
            math.degrees(problem.yaw_change),
            (math.degrees(exact), math.degrees(exact)),
            message=(
                f"a robot with one joint turns the spacecraft alike along every path between "
                f"these joints: by {math.degrees(exact):.9g} deg about {_axis_name(problem.axis)}"
                f", not the {math.degrees(wrap_angle(problem.yaw_change)):.9g} deg asked; its "
                f"goal attitude can only be base_quaternion_xyzw = "
                f"{[float(v) for v in reached]} (to {tolerance:.2g} rad)"
            ),
        )
    return replace(problem, bounds=PlanarBounds(gain, gain), yaw_change=exact + off)


def _one_attitude(reached: np.ndarray, off: float, tolerance: float) -> str:
    """A spatial one-joint robot's refusal: the one attitude it reaches (rad)."""
    return (
        "a robot with one joint turns the spacecraft alike along every path between these "
        f"joints: its goal attitude can only be base_quaternion_xyzw = "
        f"{[float(v) for v in reached]} (to {tolerance:.2g} rad), {math.degrees(off):.6g} deg "
        "from the one asked"
    )


def _checked_inputs(
    robot: Robot,
    start: np.ndarray,
    goal: np.ndarray,
    start_quaternion: np.ndarray,
    goal_quaternion: np.ndarray,
    duration: float,
) -> list[np.ndarray]:
    """Check :func:`build_problem`'s numbers; return the two attitudes as unit quaternions.

    Raises the errors :func:`build_problem` lists for them (joints in rad or m, duration in s).
    """
    for name, arr in (("start joints", start), ("goal joints", goal)):
        _check_finite(name, arr)
    if not (isinstance(duration, (int, float)) and math.isfinite(duration) and duration > 0.0):
        raise InputError(f"duration must be a finite number of seconds > 0, got {duration!r}")
    check_duration(duration)
    check_joint_count(robot.n, repr(robot.name))
    quats = []
    for name, quat in (("start attitude", start_quaternion), ("goal attitude", goal_quaternion)):
        quat = np.asarray(quat, dtype=float)
        _check_finite(name, quat)
        norm = float(np.linalg.norm(quat))
        if quat.shape != (4,) or norm < 1e-9:
            raise InputError(f"{name} must be a non-zero quaternion [x, y, z, w]")
        quats.append(quat / norm)
    check_joint_limits(robot, start, "start")
    check_joint_limits(robot, goal, "goal")
    return quats


def _planar_yaw_change(quats: Sequence[np.ndarray], axis: np.ndarray) -> float:
    """The turn from the start to the goal attitude about the planar ``axis`` (rad, wrapped).

    Raises:
        InfeasibleError: the goal is turned about other axes too (a planar base cannot).
    """
    relative = relative_rotvec(quats[0], quats[1])
    off_axis = float(np.linalg.norm(relative - (relative @ axis) * axis))
    if off_axis > 1e-9:
        raise InfeasibleError(
            math.degrees(off_axis),
            (0.0, 0.0),
            message=(
                f"this robot is planar: its base turns only about {_axis_name(axis)}, but the "
                "goal "
                f"attitude is {math.degrees(off_axis):.6g} deg away from the start about "
                "other axes; give the goal the start's pitch and roll"
            ),
            off_axis=True,
        )
    return wrap_angle(float(relative @ axis))


def _free_counts(
    robot: Robot, extra: Sequence[int] | Mapping[str, int] | None, planar: bool
) -> list[int]:
    """Free coefficients per joint beyond the quintic (see :func:`build_problem`'s ``extra``).

    Raises:
        InputError: a negative count; InputLimitError: a count beyond freefloat's limit.
    """
    if extra is None:
        counts = [0] * robot.n
        for i in range(1 if planar else 3):
            counts[i % robot.n] += 1
    elif isinstance(extra, Mapping):
        counts = [0] * robot.n
        for name, count in extra.items():
            index = robot.joint_names.index(robot.joint(name).name)
            counts[index] = int(count)
    else:
        counts = [int(c) for c in extra]
    if any(c < 0 for c in counts):
        raise InputError(f"free coefficient counts must be >= 0, got {counts}")
    for name, count in zip(robot.joint_names, counts, strict=False):
        check_extra(count, f"free coefficients of {name!r}")
    return counts


def problem_from_scenario(
    scenario: Scenario,
    extra: Sequence[int] | Mapping[str, int] | None = None,
    goal_offset: np.ndarray | None = None,
    mmap: MomentumMap | None = None,
    check_bounds: bool = True,
) -> Problem:
    """The problem a scenario states (the one way from a scenario to a problem).

    Args:
        scenario: the request; a Cartesian goal is resolved here by inverse kinematics.
        extra: free coefficients per joint; default the scenario's ``[path] extra`` (and when
            that is absent too, :func:`build_problem`'s default).
        goal_offset: added to the goal joints (rad or m), e.g. whole turns of continuous
            joints.
        mmap: momentum-map evaluator to reuse.
        check_bounds: refuse planar requests outside the planar bounds.
    """
    goal = scenario.goal if goal_offset is None else scenario.goal + goal_offset
    return build_problem(
        scenario.robot,
        scenario.start,
        goal,
        scenario.start_attitude,
        scenario.goal_attitude,
        scenario.duration,
        extra=scenario.extra if extra is None else extra,
        mmap=mmap,
        check_bounds=check_bounds,
    )

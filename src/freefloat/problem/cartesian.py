"""Cartesian goals: inverse kinematics of the free-floating system.

A goal may give the position (m, inertial frame, origin at the system CM) and, optionally, the
orientation of one or more end-effector frames instead of joint values. With the base attitude
fixed by the goal and the base position fixed by the CM staying at the origin, every frame's
pose is a function of the joint values alone; the goal joints are found by bounded least
squares (:mod:`.box_least_squares`) over the joints that move a goal frame (the others hold
their start or given goal value), from the start joints (so the nearest solution is
preferred), then from further starts.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError, UnreachableGoalError
from ..physics.momentum import MomentumMap
from ..robot.model import Robot
from .bounds import joint_ranges
from .box_least_squares import box_least_squares
from .quasi_random import unit_points

__all__ = ["FrameGoal", "solve_cartesian_goal", "solve_frame_goals", "workspace_radius"]

#: Accepted end-effector error (m, and rad for orientation).
TOLERANCE = 1e-9


def _bounds(mmap: MomentumMap) -> tuple[np.ndarray, np.ndarray]:
    lower = np.array([j.lower for j in mmap.robot.joints])
    upper = np.array([j.upper for j in mmap.robot.joints])
    return lower, upper


def workspace_radius(
    mmap: MomentumMap, quaternion_xyzw: np.ndarray, samples: int = 512, frame: str | None = None
) -> float:
    """Largest distance of an end effector from the system CM (m), sampled and refined.

    An estimate from below: the largest distance found by sampling configurations within the
    joint limits and refining the best ones. ``frame``: which end effector (default the
    robot's first).
    """
    ranges = joint_ranges(mmap)
    unit = unit_points(samples, len(ranges), 1)
    points = ranges[:, 0] + unit * (ranges[:, 1] - ranges[:, 0])
    index_of = mmap.model.getFrameId(frame or mmap.robot.end_effector)

    def distance(q: np.ndarray) -> float:
        return float(np.linalg.norm(_placement(mmap, q, quaternion_xyzw, index_of).translation))

    from scipy.optimize import minimize  # an unreachable goal's message only: lazily

    values = np.array([distance(p) for p in points])
    best = float(values.max())
    for index in np.argsort(values)[-3:]:
        result = minimize(
            lambda q: -distance(q),
            points[index],
            method="L-BFGS-B",
            bounds=[tuple(r) for r in ranges],
        )
        best = max(best, -float(result.fun))
    return best


@dataclass(frozen=True)
class FrameGoal:
    """A wanted pose of one end-effector frame, from the system CM in the inertial frame.

    Attributes:
        frame: the end-effector frame's name.
        position: wanted position (m).
        rotation: wanted orientation (3 x 3), or None for position only.
    """

    frame: str
    position: np.ndarray
    rotation: np.ndarray | None = None


def _placement(mmap: MomentumMap, q: np.ndarray, quat: np.ndarray, frame: int) -> pin.SE3:
    config = mmap.configuration(q, quat)
    pin.framesForwardKinematics(mmap.model, mmap.data, config)
    return mmap.data.oMf[frame]


def solve_cartesian_goal(
    mmap: MomentumMap,
    position: np.ndarray,
    base_quaternion_xyzw: np.ndarray,
    start_joints: np.ndarray,
    rotation: np.ndarray | None = None,
    starts: int = 8,
) -> np.ndarray:
    """Joint values (rad or m) that put the first end effector at ``position`` (``rotation``).

    The joints that move it are solved for; every other joint keeps its start value (see
    :func:`solve_frame_goals`).
    """
    goal = FrameGoal(mmap.robot.end_effector, np.asarray(position, dtype=float), rotation)
    return solve_frame_goals(mmap, [goal], base_quaternion_xyzw, start_joints, starts=starts)


def solve_frame_goals(
    mmap: MomentumMap,
    goals: Sequence[FrameGoal],
    base_quaternion_xyzw: np.ndarray,
    start_joints: np.ndarray,
    held: Mapping[str, float] | None = None,
    starts: int = 8,
) -> np.ndarray:
    """Joint values (rad or m) that put every goal frame at its pose at once.

    Only the joints that move a goal frame (its chain from the base) and are not in ``held``
    are solved for; the others keep their ``held`` value, or their start value. The base
    attitude is the goal's and the system CM stays at the origin, so moving any joint (an idle
    arm too) moves the base and with it every frame: all goals are solved together.

    Args:
        mmap: momentum map of the robot.
        goals: the wanted frame poses (m; rotation 3 x 3 or None), inertial frame, CM origin.
        base_quaternion_xyzw: base attitude at the goal.
        start_joints: the start configuration (N values, rad or m), tried first, so the nearest
            solution is preferred.
        held: joint goals given by name (rad or m): these joints do not move for the goals.
        starts: number of starting configurations tried.

    Raises:
        UnreachableGoalError: no configuration within the joint limits reaches every goal;
            gives the worst miss and that frame's workspace radius.
        InputError: a goal frame no free joint moves.
    """
    robot = mmap.robot
    held = dict(held or {})
    base = np.asarray(start_joints, dtype=float).copy()
    for name, value in held.items():
        base[robot.joint_names.index(name)] = value
    moving: set[str] = set()
    for goal in goals:
        chain = [j for j in robot.supporting_joints(goal.frame) if j not in held]
        if not chain:
            raise InputError(
                f"no free joint moves end effector {goal.frame!r}: its joints are all given "
                "as joint goals; leave some out or drop its Cartesian goal"
            )
        moving.update(chain)
    free = np.array([i for i, j in enumerate(robot.joint_names) if j in moving], dtype=int)
    frames = [mmap.model.getFrameId(goal.frame) for goal in goals]
    lower, upper = _bounds(mmap)
    lower, upper = lower[free], upper[free]
    quat = base_quaternion_xyzw

    def full(x: np.ndarray) -> np.ndarray:
        q = base.copy()
        q[free] = x
        return q

    def residual(x: np.ndarray) -> np.ndarray:
        config = mmap.configuration(full(x), quat)
        pin.framesForwardKinematics(mmap.model, mmap.data, config)
        errors = []
        for goal, frame in zip(goals, frames, strict=True):
            pose = mmap.data.oMf[frame]
            errors.append(pose.translation - goal.position)
            if goal.rotation is not None:
                errors.append(pin.log3(goal.rotation.T @ pose.rotation))
        return np.concatenate(errors)

    ranges = joint_ranges(mmap)[free]
    rng = np.random.default_rng(0)
    guesses = [np.clip(base[free], lower, upper)]
    guesses += [rng.uniform(ranges[:, 0], ranges[:, 1]) for _ in range(starts - 1)]
    best_x, best = guesses[0], math.inf
    for guess in guesses:
        result = box_least_squares(residual, guess, lower, upper, target=1e-3 * TOLERANCE)
        error = result.norm
        if error < best:
            best_x, best = result.x, error
        if best < TOLERANCE:
            return _nearest_turns(robot, full(np.asarray(best_x, dtype=float)), base)
    raise _unreachable(mmap, goals, frames, full(best_x), quat, len(free))


def _nearest_turns(robot: Robot, joints: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``joints`` (rad or m) with each turning joint's value a whole turn nearer ``start``.

    A turning joint's value and that value plus whole turns place every frame alike, so the
    goal's pose stays met; of those within the joint's limits, the one nearest the start
    joint's (an unlimited wrist solved at -209 deg where 151 deg is the same pose) asks the
    path for less travel.
    """
    out = joints.copy()
    for i, joint in enumerate(robot.joints):
        if joint.angular:
            nearer = start[i] + math.remainder(out[i] - start[i], 2.0 * math.pi)
            if joint.lower <= nearer <= joint.upper:
                out[i] = nearer
    return out


def _unreachable(
    mmap: MomentumMap,
    goals: Sequence[FrameGoal],
    frames: Sequence[int],
    closest: np.ndarray,
    quat: np.ndarray,
    free: int,
) -> UnreachableGoalError:
    """The error for goals missed, naming the worst-missed frame's goal and its miss (m, deg).

    ``closest``: the configuration the least squares ended nearest (rad or m); ``free``: the
    number of joints that were free to meet the goals. The message gives the miss of the
    worst-missed frame's position in m and, for a pose goal, of its orientation in deg; where
    that goal is a pose and the goals fix more numbers than there are free joints (3 per
    position, 6 per pose: a planar robot's in-plane goals fix fewer, so a position goal gets
    no such clause), it says so.
    """
    placements = [pin.SE3(_placement(mmap, closest, quat, f)) for f in frames]
    misses = [
        float(np.linalg.norm(p.translation - g.position))
        for g, p in zip(goals, placements, strict=True)
    ]
    k = int(np.argmax(misses))
    worst = goals[k]
    miss = f"{misses[k]:.3g} m"
    if worst.rotation is not None:
        angle = float(np.linalg.norm(pin.log3(worst.rotation.T @ placements[k].rotation)))
        miss += f" and {math.degrees(angle):.3g} deg"
    radius = workspace_radius(mmap, quat, frame=worst.frame)  # reuses the model's data
    what = "pose" if worst.rotation is not None else "position"
    named = f" ({worst.frame!r})" if len(goals) > 1 else ""
    fixed = sum(3 if g.rotation is None else 6 for g in goals)
    few = ""
    if worst.rotation is not None and fixed > free:  # more numbers asked than joints
        few = (
            f"; the goals fix {fixed} numbers and {free} joints are free to meet them: a "
            "position alone may be met"
        )
    return UnreachableGoalError(
        f"end-effector goal{named} {what} {np.round(worst.position, 4).tolist()} m is out of "
        f"reach: the closest configuration within the joint limits misses it by {miss} (a "
        f"goal is met within {TOLERANCE:g} m and rad); the workspace radius from the system "
        f"CM is about {radius:.3f} m{few}",
        distance=misses[k],
        radius=radius,
    )

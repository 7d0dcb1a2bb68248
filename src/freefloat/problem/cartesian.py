"""Cartesian goals: inverse kinematics of the free-floating system.

A goal may give the end-effector position (m, inertial frame, origin at the system CM) and,
optionally, its orientation instead of joint values. With the base attitude fixed by the goal
and the base position fixed by the CM staying at the origin, the end-effector pose is a
function of the joint values alone; the goal joints are found by bounded least squares from
the start joints (so the nearest solution is preferred), then from further starts.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from scipy.optimize import least_squares, minimize
from scipy.stats import qmc

from ..errors import UnreachableGoalError
from ..physics.momentum import MomentumMap
from .bounds import joint_ranges

__all__ = ["solve_cartesian_goal", "workspace_radius"]

#: Accepted end-effector error (m, and rad for orientation).
TOLERANCE = 1e-9


def _bounds(mmap: MomentumMap) -> tuple[np.ndarray, np.ndarray]:
    lower = np.array([j.lower for j in mmap.robot.joints])
    upper = np.array([j.upper for j in mmap.robot.joints])
    return lower, upper


def workspace_radius(mmap: MomentumMap, quaternion_xyzw: np.ndarray, samples: int = 512) -> float:
    """Largest end-effector distance from the system CM (m), sampled and refined.

    An estimate from below: the largest distance found by sampling configurations within the
    joint limits and refining the best ones.
    """
    ranges = joint_ranges(mmap)
    unit = qmc.Sobol(len(ranges), scramble=True, seed=1).random(samples)
    points = ranges[:, 0] + unit * (ranges[:, 1] - ranges[:, 0])

    def distance(q: np.ndarray) -> float:
        return float(np.linalg.norm(mmap.end_effector_pose(q, quaternion_xyzw).translation))

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


def solve_cartesian_goal(
    mmap: MomentumMap,
    position: np.ndarray,
    base_quaternion_xyzw: np.ndarray,
    start_joints: np.ndarray,
    rotation: np.ndarray | None = None,
    starts: int = 8,
) -> np.ndarray:
    """Joint values (rad or m) that put the end effector at ``position`` (and ``rotation``).

    Args:
        mmap: momentum map of the robot.
        position: wanted end-effector position (m), inertial frame, origin at the system CM.
        base_quaternion_xyzw: base attitude at the goal.
        start_joints: the start configuration, tried first (nearest solution preferred).
        rotation: wanted end-effector orientation (3 x 3), or None for position only.
        starts: number of starting configurations tried.

    Raises:
        UnreachableGoalError: no configuration within the joint limits reaches the goal; gives
            the closest distance and the workspace radius.
    """
    position = np.asarray(position, dtype=float)
    lower, upper = _bounds(mmap)

    def residual(q: np.ndarray) -> np.ndarray:
        pose = mmap.end_effector_pose(q, base_quaternion_xyzw)
        error = pose.translation - position
        if rotation is not None:
            error = np.concatenate([error, pin.log3(rotation.T @ pose.rotation)])
        return error

    ranges = joint_ranges(mmap)
    rng = np.random.default_rng(0)
    guesses = [np.clip(start_joints, lower, upper)]
    guesses += [rng.uniform(ranges[:, 0], ranges[:, 1]) for _ in range(starts - 1)]
    best_q, best = guesses[0], math.inf
    for guess in guesses:
        result = least_squares(
            residual,
            guess,
            bounds=(lower, upper),
            method="trf",
            jac="3-point",
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        )
        error = float(np.linalg.norm(result.fun))
        if error < best:
            best_q, best = result.x, error
        if best < TOLERANCE:
            return np.asarray(best_q, dtype=float)
    radius = workspace_radius(mmap, base_quaternion_xyzw)
    what = "pose" if rotation is not None else "position"
    raise UnreachableGoalError(
        f"end-effector goal {what} {np.round(position, 4).tolist()} m is out of reach: the "
        f"closest configuration within the joint limits misses it by {best:.3g}; the workspace "
        f"radius from the system CM is about {radius:.3f} m",
        distance=best,
        radius=radius,
    )

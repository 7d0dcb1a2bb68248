"""The numbers of a plan, computed from its problem and free coefficients.

One function per record: :func:`sample_solution` (the ``samples`` section: joints, base pose
and rate, every end effector and torques at equally spaced instants), :func:`base_report` (the
attitudes at start, goal and as reached), :func:`feasibility_report` (the planar bounds and the
request), :func:`solution_record` (a root's free parameters, residual and path length). The
planning pipeline writes a plan with them, and :mod:`freefloat.verify` recomputes a plan file's
numbers with the very same functions, so that a genuine plan agrees with its recomputation to
rounding. Units: s, rad (m for prismatic joints and positions), N m (N); ``_deg`` fields in
degrees. Positions are in the inertial frame whose origin is the system CM (docs/method.md
section 10).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..physics.attitude import geodesic_angle, quat_rotate, zyx_from_quat, zyx_from_quats
from ..physics.dynamics import inverse_dynamics_batch
from ..problem.paths import excursions
from ..problem.residual import Problem
from .records import BaseReport, Feasibility, PathQuality, Samples, SolutionRecord

__all__ = [
    "base_report",
    "degrees",
    "feasibility_report",
    "free_parameters",
    "path_quality",
    "sample_solution",
    "solution_record",
]


def degrees(values: Sequence[float] | np.ndarray) -> list[float]:
    """Angles in rad as a list of degrees."""
    if isinstance(values, np.ndarray):
        values = values.tolist()
    return [math.degrees(float(v)) for v in values]


def sample_solution(problem: Problem, beta: np.ndarray, count: int) -> Samples:
    """The path at ``beta`` sampled at ``count`` equally spaced instants of [0, T].

    Joints from the path family, base attitude integrated as the planner does
    (:meth:`Problem.attitudes`, steps no longer than the problem's grid), joint torques, base
    twist, CM and end effector by inverse dynamics (:func:`inverse_dynamics_batch`); base
    position and end effector are rotated into the inertial frame with its origin at the CM.
    """
    duration = problem.duration
    s = np.linspace(0.0, 1.0, max(2, int(count)))
    t = s * duration
    path = problem.family.at_times(beta, t, duration)
    quats = problem.attitudes(beta, s)
    dyn = inverse_dynamics_batch(problem.mmap, path.q, path.qd, path.qdd)
    frames = problem.robot.end_effectors
    paths = [quat_rotate(quats, ee - dyn.com) for ee in dyn.end_effectors]
    return Samples(
        t=np.array(t, dtype=float),
        q=np.array(path.q, dtype=float),
        qd=np.array(path.qd, dtype=float),
        qdd=np.array(path.qdd, dtype=float),
        base_position=quat_rotate(quats, -dyn.com),
        base_quaternion_xyzw=np.array(quats, dtype=float),
        base_zyx_deg=np.degrees(zyx_from_quats(quats)),  # math.degrees' product, batched
        end_effector_position=paths[0],
        base_angular_velocity=np.array(dyn.base_twist[:, 3:], dtype=float),
        tau=np.array(dyn.tau, dtype=float),
        end_effector_paths=dict(zip(frames, paths, strict=True)),
    )


def base_report(problem: Problem, beta: np.ndarray) -> BaseReport:
    """Start, target and reached base attitude (the reached one on the problem's grid)."""
    achieved = problem.achieved(beta)
    return BaseReport(
        start_quaternion_xyzw=problem.start_quaternion.tolist(),
        target_quaternion_xyzw=problem.goal_quaternion.tolist(),
        achieved_quaternion_xyzw=achieved.tolist(),
        start_zyx_deg=degrees(zyx_from_quat(problem.start_quaternion)),
        target_zyx_deg=degrees(zyx_from_quat(problem.goal_quaternion)),
        achieved_zyx_deg=degrees(zyx_from_quat(achieved)),
        attitude_error_rad=geodesic_angle(achieved, problem.goal_quaternion),
    )


def feasibility_report(problem: Problem) -> Feasibility:
    """The planar bounds of the joint motion and the requested yaw change (deg)."""
    bounds = problem.bounds_interval
    return Feasibility(
        planar=problem.planar,
        yaw_change_bounds_deg=None if bounds is None else degrees(bounds),
        requested_yaw_change_deg=(
            None if problem.yaw_change is None else math.degrees(problem.yaw_change)
        ),
    )


def solution_record(
    problem: Problem, beta: np.ndarray, residual: float, path_length: float
) -> SolutionRecord:
    """One root as the plan file records it: its free parameters (rad or m, per joint)."""
    return SolutionRecord(
        free_parameters=free_parameters(problem, beta),
        residual_rad=residual,
        path_length=path_length,
    )


def free_parameters(problem: Problem, beta: np.ndarray) -> dict[str, list[float]]:
    """Per joint, its entries of ``beta`` (the basis coefficients, rad or m) in basis order."""
    out: dict[str, list[float]] = {name: [] for name in problem.robot.joint_names}
    names = problem.robot.joint_names
    for value, (joint, _) in zip(np.asarray(beta, float), problem.family.free_index, strict=True):
        out[names[joint]].append(float(value))
    return out


def path_quality(problem: Problem, beta: np.ndarray) -> PathQuality:
    """Excursions beyond the start-goal spans (deg; m for prismatic) and RMS deviation (deg)."""
    family = problem.family
    beyond = excursions(problem.polynomials(beta), family.start, family.goal)
    shown = [
        float(v) if joint.kind == "prismatic" else math.degrees(float(v))
        for v, joint in zip(beyond, problem.robot.joints, strict=True)
    ]
    worst = int(np.argmax(shown))
    return PathQuality(
        excursion_beyond_span=dict(zip(problem.robot.joint_names, shown, strict=True)),
        largest_excursion=shown[worst],
        largest_joint=problem.robot.joint_names[worst],
        deviation_rms_deg=math.degrees(math.sqrt(float(np.dot(beta, beta)))),
    )

"""The checks of a plan that need no integration: momentum, centre of mass, wrench, ends, samples.

Each check is a function of a :class:`Subject` (the plan, its robot, the file's joint paths)
returning its typed :class:`~freefloat.plans.guarantees.Check` records, each with its value,
tolerance (:data:`TOLERANCES`) and unit; these are exact up to rounding (``error_estimate`` 0).
The integrating checks are in :mod:`freefloat.verify.integrating`; the list of all of them is
:data:`freefloat.verify.checks.PLAN_CHECKS`.

- ``momentum``: largest total momentum (Pinocchio's centroidal momentum) along the samples,
  using the sampled joints, joint rates, base attitude and base angular rate (kg m^2/s);
  relative to the arm's own momentum scale. ``cm_offset``: the sampled base positions keep the
  system CM at the origin (m).
- ``base_wrench``: the base entries of the inverse dynamics behind the samples (N, N m),
  relative to the torque scale.
- ``boundary``: position, rate and acceleration errors of the paths at both ends (rad, rad/s,
  rad/s^2, times powers of the duration), against the requested start and goal, relative to
  the joint travel.
- ``samples``: the sampled joints, rates and accelerations are the paths, sampled (relative, as
  ``boundary``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..physics.dynamics import inverse_dynamics_batch
from ..physics.momentum import MomentumMap
from ..plans.format import Plan
from ..plans.guarantees import Check
from ..robot.model import Robot
from .along import PathDynamics
from .path_eval import FilePath

__all__ = [
    "TOLERANCES",
    "PlanCheck",
    "Subject",
    "base_wrench_check",
    "boundary_check",
    "momentum_checks",
    "samples_check",
]

#: Pass thresholds of the checks (see the module docstrings for units).
TOLERANCES: dict[str, float] = {
    "momentum_relative": 1e-9,
    "cm_offset_m": 1e-9,
    "base_wrench_relative": 1e-8,
    "attitude_independent_rad": 1e-7,
    "replay_attitude_rad": 1e-4,
    "replay_joint": 1e-4,
    "boundary_relative": 1e-9,
    "samples_relative": 1e-9,
}


@dataclass(frozen=True)
class Subject:
    """What every check of a plan reads.

    Attributes:
        plan: the plan.
        robot: its robot, loaded from its URDF.
        mmap: the robot's momentum map.
        path: the plan's joint paths as its file defines them (:mod:`.path_eval`).
        replay_steps: the most Runge-Kutta steps the forward-dynamics replay may take.
    """

    plan: Plan
    robot: Robot
    mmap: MomentumMap
    path: FilePath
    replay_steps: int

    @functools.cached_property
    def dynamics(self) -> PathDynamics:
        """Torques and base angular velocity of the file's paths, shared by the checks."""
        return PathDynamics(self.mmap, self.path)

    @property
    def start(self) -> np.ndarray:
        """The requested start joints (rad or m)."""
        return np.asarray(self.plan.request.start_joints, dtype=float)

    @property
    def goal(self) -> np.ndarray:
        """The requested goal joints (rad or m)."""
        return np.asarray(self.plan.request.goal_joints, dtype=float)

    @property
    def travel(self) -> np.ndarray:
        """Per joint, ``max(1, |goal - start|)`` (rad or m): the scale of relative checks."""
        return np.maximum(1.0, np.abs(self.goal - self.start))


#: A check of a plan: its records, in the order the plan file lists them.
PlanCheck = Callable[[Subject], list[Check]]


def momentum_checks(subject: Subject) -> list[Check]:
    """``momentum`` and ``cm_offset`` along the samples, at the sampled base pose."""
    samples, model = subject.plan.samples, subject.robot.model
    data = model.createData()
    configs = subject.mmap.configurations(np.asarray(samples.q, float))
    configs[:, 0:3] = np.asarray(samples.base_position, float)
    configs[:, 3:7] = np.asarray(samples.base_quaternion_xyzw, float)
    # The CM from Pinocchio's own computation at each sample (data.com, which the map
    # computes on the way), not from the map's entries as the planner reads it.
    ag = np.empty((len(configs), 6, model.nv))
    com = np.empty((len(configs), 3))
    for k, config in enumerate(configs):
        ag[k] = pin.computeCentroidalMap(model, data, config)
        com[k] = data.com[0]
    arm = np.einsum("kij,kj->ki", ag[:, :, 6:], np.asarray(samples.qd, float))
    linear = -np.linalg.solve(ag[:, :, :6], arm[..., None])[:, :3, 0]
    v_base = np.concatenate([linear, np.asarray(samples.base_angular_velocity, float)], axis=1)
    momentum = np.einsum("kij,kj->ki", ag[:, :, :6], v_base) + arm
    momentum_max = float(np.linalg.norm(momentum, axis=1).max())
    momentum_scale = float(np.linalg.norm(arm, axis=1).max())
    cm_max = float(np.linalg.norm(com, axis=1).max())
    return [
        Check(
            "momentum",
            momentum_max,
            TOLERANCES["momentum_relative"] * max(1.0, momentum_scale),
            "kg m^2/s",
        ),
        Check("cm_offset", cm_max, TOLERANCES["cm_offset_m"], "m"),
    ]


def base_wrench_check(subject: Subject) -> list[Check]:
    """``base_wrench``: the base entries of the inverse dynamics of the samples, recomputed."""
    samples = subject.plan.samples
    dyn = inverse_dynamics_batch(
        subject.mmap,
        np.asarray(samples.q, float),
        np.asarray(samples.qd, float),
        np.asarray(samples.qdd, float),
    )
    wrench_max = float(np.abs(dyn.base_wrench).max())
    torque_scale = float(np.abs(dyn.tau).max())
    tolerance = TOLERANCES["base_wrench_relative"] * max(1.0, torque_scale)
    return [Check("base_wrench", wrench_max, tolerance, "N, N m")]


def boundary_check(subject: Subject) -> list[Check]:
    """``boundary``: the largest end-condition error, relative to duration and joint travel."""
    path, start, goal = subject.path, subject.start, subject.goal
    T = path.duration
    q, qd, qdd = path(np.array([0.0, T]))
    position = np.maximum(np.abs(q[0] - start), np.abs(q[1] - goal))
    rates = np.abs(qd).max(axis=0) * T
    accelerations = np.abs(qdd).max(axis=0) * T**2
    worst = np.maximum.reduce([position, rates, accelerations]) / subject.travel
    return [Check("boundary", float(worst.max()), TOLERANCES["boundary_relative"], "1")]


def samples_check(subject: Subject) -> list[Check]:
    """``samples``: the sampled joints, rates and accelerations are the paths, sampled."""
    samples, duration = subject.plan.samples, subject.plan.duration
    exact = subject.path(np.asarray(samples.t, float))
    stored = (np.asarray(samples.q, float), np.asarray(samples.qd, float), samples.qdd)
    worst = max(
        float((np.abs(np.asarray(got, float) - want) * duration**power / subject.travel).max())
        for got, want, power in zip(stored, exact, (0, 1, 2), strict=True)
    )
    return [Check("samples", worst, TOLERANCES["samples_relative"], "1")]

"""Independent verification of a plan, from the plan file alone.

Checks, each with a documented tolerance (:data:`TOLERANCES`):

- ``momentum_max``: largest total momentum (Pinocchio's centroidal momentum) along the samples,
  using the sampled joints, joint rates, base attitude and base angular rate; relative to the
  arm's own momentum scale. ``cm_offset_max``: the sampled base positions keep the system CM
  at the origin (m).
- ``base_wrench_max``: the base entries of the inverse dynamics behind ``samples.tau`` (N, N m),
  relative to the torque scale.
- ``attitude_error_independent_rad``: the final attitude from a classical RK4 integration of
  the quaternion ODE in seconds along the plan's polynomials (not the planner's Magnus scheme).
- ``replay``: forward dynamics of the free system (ABA, RK4) driven only by the planned joint
  torques from the start at rest: final attitude error (rad) and joint error (rad or m).

- ``boundary``: position, rate and acceleration errors of the polynomials at both ends (rad,
  rad/s, rad/s^2), against the requested start and goal, relative to the joint travel.
- ``joint_limit_excess``: how far the sampled joints go beyond their URDF limits (rad or m).

Both integrating checks double their steps and report the difference between the last two
results as their ``error_estimate`` (see :func:`verify_plan` and :func:`_decided`); the other
checks are exact up to rounding.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..errors import FreeFloatError, PlanFileError
from ..physics.attitude import geodesic_angle
from ..physics.dynamics import inverse_dynamics, inverse_dynamics_batch, replay
from ..physics.momentum import MomentumMap
from ..plans.format import FORMAT_2, FORMAT_3, Check, Plan, Verification
from ..plans.robot_copy import plan_robot
from ..problem.constraints import Constraint, JointEffortLimits, constraint_from_record
from ..problem.constraints.clearance import Clearance
from ..problem.constraints.registry import clearance_constraint
from ..robot.collision import Obstacle
from ..robot.model import Robot
from .clearance_check import clearance_checks
from .path_eval import FilePath, file_path
from .recompute import check_plan_numbers, compare_verification
from .stepping import (
    _FIRST_ATTITUDE_STEPS,
    _FIRST_REPLAY_STEPS,
    _MAX_ATTITUDE_STEPS,
    CONVERGED_FRACTION,
    MAX_REPLAY_STEPS,
    _decided,
    _finite,
    _refine,
    _rk4_attitude,
    _with_midpoints,
)

__all__ = [
    "CONVERGED_FRACTION",
    "MAX_REPLAY_STEPS",
    "REPLAY_STEPS_LIMIT",
    "TOLERANCES",
    "joint_torque_function",
    "plan_constraints",
    "verify_plan",
]

#: The most replay steps a caller may allow (``--replay-steps``): 65536 RK4 steps.
REPLAY_STEPS_LIMIT = 1 << 16

#: Pass thresholds of the checks (see the module docstring for units).
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


#: Checks an older file cannot state as they are made now: effort (a /2 file predates it) and
#: clearance (before format 4: sampled on the meshes' own faces). Their stated figures are not
#: compared; the checks made now still decide whether the plan passes.
_CLEARANCE_CHECKS = ("clearance", "clearance_hull_agreement")
_PREDATED: dict[str, tuple[str, ...]] = {
    FORMAT_2: (JointEffortLimits.name, *_CLEARANCE_CHECKS),
    FORMAT_3: _CLEARANCE_CHECKS,
}


def _polys(plan: Plan) -> FilePath:
    """The plan's joint paths as its file defines them (:mod:`.path_eval`)."""
    return file_path(plan)


def _state(path: FilePath, t: float) -> tuple[np.ndarray, ...]:
    return tuple(x[0] for x in path(np.array([t])))


def joint_torque_function(plan: Plan, mmap: MomentumMap) -> Callable[[float], np.ndarray]:
    """``tau(t)``: joint torques (N m or N) of the plan at any time t (s), from its polynomials."""
    coeffs = _polys(plan)

    def tau(t: float) -> np.ndarray:
        q, qd, qdd = _state(coeffs, t)
        return inverse_dynamics(mmap, q, qd, qdd).tau

    return tau


def plan_constraints(plan: Plan, robot: Robot) -> list[Constraint]:
    """The constraints a plan states it honours, rebuilt from the registry by their records.

    Every ``constraints`` record, and clearance when its ``safety`` record says it was checked.
    A file written before constraint records is held to what its format promised
    (:data:`~freefloat.plans.format.PROMISED`: a ``freefloat.plan/2`` file, no effort limits).

    Raises:
        PlanFileError: a record names a constraint this freefloat does not know, or a bad
            parameter.
    """
    constraints = []
    for i, record in enumerate(plan.constraints):
        try:
            constraints.append(constraint_from_record(record.name, record.parameters))
        except FreeFloatError as exc:
            raise PlanFileError(f"plan field 'constraints[{i}]': {exc}") from None
    if plan.safety.checked:
        obstacles = [
            Obstacle(o.name, o.shape, tuple(o.size), tuple(o.xyz), tuple(o.rpy))  # type: ignore[arg-type]
            for o in plan.safety.obstacles
        ]
        clearance = clearance_constraint(robot, plan.safety.srdf, obstacles, plan.safety.margin_m)
        if clearance is not None:
            constraints.append(clearance)
    return constraints


def _path_at(path: FilePath, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint values, rates and accelerations (K, N) of the plan's paths at times ``t`` (s)."""
    return path(np.asarray(t, dtype=float))


def _boundary(path: FilePath, start: np.ndarray, goal: np.ndarray) -> float:
    """Largest end-condition error, relative to the duration and the joint travel (>= 1)."""
    T = path.duration
    q, qd, qdd = path(np.array([0.0, T]))
    travel = np.maximum(1.0, np.abs(goal - start))
    position = np.maximum(np.abs(q[0] - start), np.abs(q[1] - goal))
    rates = np.abs(qd).max(axis=0) * T
    accelerations = np.abs(qdd).max(axis=0) * T**2
    return float((np.maximum.reduce([position, rates, accelerations]) / travel).max())


def verify_plan(
    plan: Plan,
    robot: Robot | None = None,
    replay_steps: int = MAX_REPLAY_STEPS,
    constraints: list[Constraint] | None = None,
    recompute: bool = True,
) -> Verification:
    """Run every check on ``plan``; needs only the plan and its URDF.

    First every number of the plan is recomputed from its URDF, duration and coefficients and
    compared (:mod:`freefloat.verify.recompute`); then the checks run; then their figures are
    compared with those the plan states, if it states any.

    The two integrating checks estimate their own error by step doubling (the difference
    between the results on M and 2 M steps, which bounds the error of the finer one while the
    scheme converges) and refine until their verdict stands whatever that error, or their
    estimate is below :data:`CONVERGED_FRACTION` of the tolerance. Each reports the finer
    result as its value and the difference as its ``error_estimate``.

    Args:
        plan: the plan (for example from :meth:`Plan.load`).
        robot: the loaded robot, to skip reloading the URDF.
        replay_steps: the most RK4 steps the forward-dynamics replay may take (>= 1).
        constraints: path constraints to check densely; default those the plan records
            (:func:`plan_constraints`).
        recompute: recompute and compare the plan's numbers and figures (the pipeline, which
            has just computed them with the same functions, skips it).

    Raises:
        ValueError: ``replay_steps`` outside 1 to :data:`REPLAY_STEPS_LIMIT`.
        PlanMismatchError: a stored number or figure disagrees with its recomputation.
        PlanFileError: the plan's robot or request does not match its URDF.
    """
    if not 1 <= replay_steps <= REPLAY_STEPS_LIMIT:
        raise ValueError(
            f"the replay takes 1 to {REPLAY_STEPS_LIMIT} steps, got replay_steps={replay_steps}"
        )
    robot = robot or plan_robot(plan)
    if recompute:
        check_plan_numbers(plan, robot)
    constraints = plan_constraints(plan, robot) if constraints is None else constraints
    mmap = MomentumMap(robot)
    model, data = robot.model, robot.model.createData()
    samples = plan.samples
    duration = plan.duration
    coeffs = _polys(plan)
    tol = TOLERANCES

    # Momentum and CM along the samples, at the sampled base pose.
    q_s, qd_s = np.asarray(samples.q, float), np.asarray(samples.qd, float)
    qdd_s = np.asarray(samples.qdd, float)
    configs = mmap.configurations(q_s)
    configs[:, 0:3] = np.asarray(samples.base_position, float)
    configs[:, 3:7] = np.asarray(samples.base_quaternion_xyzw, float)
    ag = np.empty((len(configs), 6, model.nv))
    com = np.empty((len(configs), 3))
    for k, config in enumerate(configs):
        ag[k] = pin.computeCentroidalMap(model, data, config)
        com[k] = data.com[0]
    arm = np.einsum("kij,kj->ki", ag[:, :, 6:], qd_s)
    linear = -np.linalg.solve(ag[:, :, :6], arm[..., None])[:, :3, 0]
    v_base = np.concatenate([linear, np.asarray(samples.base_angular_velocity, float)], axis=1)
    momentum = np.einsum("kij,kj->ki", ag[:, :, :6], v_base) + arm
    momentum_max = float(np.linalg.norm(momentum, axis=1).max())
    momentum_scale = float(np.linalg.norm(arm, axis=1).max())
    cm_max = float(np.linalg.norm(com, axis=1).max())

    # Torques' base wrench, recomputed.
    dyn = inverse_dynamics_batch(mmap, q_s, qd_s, qdd_s)
    wrench_max = float(np.abs(dyn.base_wrench).max())
    torque_scale = float(np.abs(dyn.tau).max())

    # Independent attitude integration: RK4 on the quaternion ODE in seconds, step doubling.
    start_quat = np.asarray(plan.base.start_quaternion_xyzw, dtype=float)
    target = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)

    def omega_at(t: np.ndarray) -> np.ndarray:
        q, qd, _ = _path_at(coeffs, t)
        return mmap.base_rates(q, qd).omega

    steps, omega = _FIRST_ATTITUDE_STEPS, None
    omega = _refine(None, steps, duration, omega_at)
    coarse = _rk4_attitude(start_quat, omega, duration)
    previous_estimate = math.inf
    while True:
        steps *= 2
        omega = _refine(omega, steps, duration, omega_at)
        fine = _rk4_attitude(start_quat, omega, duration)
        attitude_independent = geodesic_angle(fine, target)
        attitude_estimate = geodesic_angle(coarse, fine)
        if steps >= _MAX_ATTITUDE_STEPS or _decided(
            attitude_independent,
            attitude_estimate,
            previous_estimate,
            tol["attitude_independent_rad"],
            float(np.abs(omega).max()) * duration / steps,
        ):
            break
        coarse, previous_estimate = fine, attitude_estimate
    attitude_steps = steps

    # Forward-dynamics replay from the start at rest, step doubling.
    start = np.asarray(plan.request.start_joints, dtype=float)
    goal = np.asarray(plan.request.goal_joints, dtype=float)

    def torque_at(t: np.ndarray) -> np.ndarray:
        q, qd, qdd = _path_at(coeffs, t)
        return inverse_dynamics_batch(mmap, q, qd, qdd).tau

    def run(ends: np.ndarray, table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        result = replay(mmap, start, start_quat, table, duration, len(ends) - 1, False, nodes=ends)
        return result.quaternion_xyzw, result.joints

    steps = min(_FIRST_REPLAY_STEPS, replay_steps)
    ends = np.linspace(0.0, duration, steps + 1)
    torques = torque_at(_with_midpoints(ends))
    coarse_q, coarse_j = run(ends, torques)
    replay_att = geodesic_angle(coarse_q, target)
    replay_joint = float(np.abs(_wrap_joints(robot, coarse_j - goal)).max())
    speed = max(float(np.abs(qd_s).max()), float(np.abs(samples.base_angular_velocity).max()), 0.0)
    att_estimate = joint_estimate = math.inf
    prev = before = (math.inf, math.inf)  # the last two differences (attitude, joints)
    converged = False
    while 2 * steps <= replay_steps:
        steps *= 2
        ends = _with_midpoints(ends)
        fine_times = _with_midpoints(ends)
        table = np.empty((len(fine_times), robot.n))
        table[0::2] = torques
        table[1::2] = torque_at(fine_times[1::2])
        torques = table
        fine_q, fine_j = run(ends, torques)
        replay_att = geodesic_angle(fine_q, target)
        replay_joint = float(np.abs(_wrap_joints(robot, fine_j - goal)).max())
        att_estimate = _finite(geodesic_angle(coarse_q, fine_q))
        joint_estimate = _finite(float(np.abs(_wrap_joints(robot, fine_j - coarse_j)).max()))
        turn = speed * duration / steps
        if _decided(
            replay_att, att_estimate, prev[0], tol["replay_attitude_rad"], turn, before[0]
        ) and _decided(replay_joint, joint_estimate, prev[1], tol["replay_joint"], turn, before[1]):
            converged = True
            break
        coarse_q, coarse_j = fine_q, fine_j
        before, prev = prev, (att_estimate, joint_estimate)
    replay_detail = f"RK4, {steps} steps"
    if not converged:
        # The steps allowed do not resolve this motion (a long, fast or sensitive one): the
        # difference bounds nothing, and the replay cannot tell its error from the value.
        # A level that blew up (a long chain's open-loop replay diverges) differs by inf: the
        # value itself is then the bound, so the file holds finite numbers.
        att_estimate = max(att_estimate, replay_att) if math.isfinite(att_estimate) else replay_att
        joint_estimate = (
            max(joint_estimate, replay_joint) if math.isfinite(joint_estimate) else replay_joint
        )
        replay_detail += ", not converged: no verdict"

    boundary = _boundary(coeffs, start, goal)
    travel = np.maximum(1.0, np.abs(goal - start))

    # The samples are the polynomials, sampled.
    exact = _path_at(coeffs, np.asarray(samples.t, float))
    worst = max(
        float((np.abs(got - want) * duration**power / travel).max())
        for got, want, power in ((q_s, exact[0], 0), (qd_s, exact[1], 1), (qdd_s, exact[2], 2))
    )

    checks = [
        Check(
            "momentum",
            momentum_max,
            tol["momentum_relative"] * max(1.0, momentum_scale),
            "kg m^2/s",
        ),
        Check("cm_offset", cm_max, tol["cm_offset_m"], "m"),
        Check(
            "base_wrench",
            wrench_max,
            tol["base_wrench_relative"] * max(1.0, torque_scale),
            "N, N m",
        ),
        Check(
            "attitude_independent",
            attitude_independent,
            tol["attitude_independent_rad"],
            "rad",
            attitude_estimate,
            f"RK4, {attitude_steps} steps",
        ),
        Check(
            "replay_attitude",
            replay_att,
            tol["replay_attitude_rad"],
            "rad",
            att_estimate,
            replay_detail,
        ),
        Check(
            "replay_joints",
            replay_joint,
            tol["replay_joint"],
            "rad|m",
            joint_estimate,
            replay_detail,
        ),
        Check("boundary", boundary, tol["boundary_relative"], "1"),
        Check("samples", worst, tol["samples_relative"], "1"),
    ]
    path = plan.path()
    for constraint in constraints:
        if isinstance(constraint, Clearance):
            checks.extend(clearance_checks(robot, constraint, coeffs))
        elif constraint.applies_to(robot):
            excess = constraint.excess(robot, path)
            checks.append(
                Check(
                    constraint.name,
                    excess.value,
                    constraint.tolerance,
                    constraint.unit,
                    excess.error_estimate,
                    excess.detail,
                )
            )
    verification = Verification(tuple(checks))
    if recompute:
        # An older file states some checks as they were made then (_PREDATED): the figures it
        # states otherwise are compared; every check made now decides whether the plan passes.
        predated = _PREDATED.get(plan.format, ())
        stated = Verification(tuple(c for c in checks if c.name not in predated))
        on_file = Verification(tuple(c for c in plan.verification.checks if c.name not in predated))
        compare_verification(on_file, stated)
    return verification


def _wrap_joints(robot: Robot, delta: np.ndarray) -> np.ndarray:
    """Joint differences, continuous joints wrapped to (-pi, pi] (rad or m)."""
    out = np.array(delta, dtype=float)
    for i, joint in enumerate(robot.joints):
        if joint.kind == "continuous":
            out[i] = math.remainder(out[i], 2.0 * math.pi)
    return out

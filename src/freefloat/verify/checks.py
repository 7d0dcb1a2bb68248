"""Independent verification of a plan, from the plan file alone.

Checks, each with a documented tolerance (:data:`TOLERANCES`):

- ``momentum_max``: largest total momentum (Pinocchio's centroidal momentum) along the samples,
  using the sampled joints, joint rates, base attitude and base angular rate; relative to the
  arm's own momentum scale. ``cm_offset_max``: the sampled base positions keep the system CM
  at the origin (m).
- ``base_wrench_max``: the base entries of the inverse dynamics behind ``samples.tau`` (N, N m),
  relative to the torque scale.
- ``attitude_error_independent_rad``: the final attitude from an adaptive DOP853 integration of
  the quaternion ODE in seconds along the plan's polynomials (not the planner's Magnus scheme).
- ``replay``: forward dynamics of the free system (ABA, RK4) driven only by the planned joint
  torques from the start at rest: final attitude error (rad) and joint error (rad or m).
- ``boundary``: position, rate and acceleration errors of the polynomials at both ends (rad,
  rad/s, rad/s^2), against the requested start and goal, relative to the joint travel.
- ``joint_limit_excess``: how far the sampled joints go beyond their URDF limits (rad or m).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

from ..errors import PlanFileError
from ..physics.attitude import geodesic_angle, quat_multiply
from ..physics.dynamics import inverse_dynamics, replay
from ..physics.momentum import MomentumMap
from ..plans.format import Check, Plan, Verification
from ..problem.constraints import Constraint, default_constraints
from ..problem.paths import JointPolynomials
from ..robot.model import Robot, load_robot

__all__ = ["TOLERANCES", "boundary_errors", "joint_torque_function", "verify_plan"]

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


def _polys(plan: Plan) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    poly = np.polynomial.polynomial
    c = [np.asarray(plan.coefficients[name], dtype=float) for name in plan.robot.joints]
    return c, [poly.polyder(x) for x in c], [poly.polyder(x, 2) for x in c]


def _state(coeffs: tuple[list[np.ndarray], ...], t: float) -> tuple[np.ndarray, ...]:
    poly = np.polynomial.polynomial
    return tuple(np.array([poly.polyval(t, c) for c in group]) for group in coeffs)


def boundary_errors(
    coefficients: list[np.ndarray], start: np.ndarray, goal: np.ndarray, duration: float
) -> dict[str, float]:
    """Boundary-condition errors of joint polynomials (ascending powers of t in s).

    Returns the largest position error against ``start`` and ``goal`` (rad or m), the largest
    end rate (per s) and acceleration (per s^2), and ``relative_max``: the largest of these
    made dimensionless by the duration and the joint travel (at least 1).
    """
    poly = np.polynomial.polynomial
    groups = (
        coefficients,
        [poly.polyder(c) for c in coefficients],
        [poly.polyder(c, 2) for c in coefficients],
    )
    q0, qd0, qdd0 = _state(groups, 0.0)
    q1, qd1, qdd1 = _state(groups, duration)
    travel = np.maximum(1.0, np.abs(goal - start))
    position = np.maximum(np.abs(q0 - start), np.abs(q1 - goal))
    rate = np.maximum(np.abs(qd0), np.abs(qd1))
    accel = np.maximum(np.abs(qdd0), np.abs(qdd1))
    relative = np.maximum.reduce([position, rate * duration, accel * duration**2]) / travel
    return {
        "position": float(position.max()),
        "rate": float(rate.max()),
        "acceleration": float(accel.max()),
        "relative_max": float(relative.max()),
    }


def joint_torque_function(plan: Plan, mmap: MomentumMap) -> Callable[[float], np.ndarray]:
    """``tau(t)``: joint torques (N m or N) of the plan at any time t (s), from its polynomials."""
    coeffs = _polys(plan)

    def tau(t: float) -> np.ndarray:
        q, qd, qdd = _state(coeffs, t)
        return inverse_dynamics(mmap, q, qd, qdd).tau

    return tau


def _robot_for(plan: Plan) -> Robot:
    robot = load_robot(plan.robot.urdf, plan.robot.end_effector)
    if robot.joint_names != list(plan.robot.joints):
        raise PlanFileError(
            f"the plan's joints {plan.robot.joints} do not match the URDF's {robot.joint_names}"
        )
    return robot


def verify_plan(
    plan: Plan,
    robot: Robot | None = None,
    replay_steps: int = 500,
    constraints: list[Constraint] | None = None,
) -> Verification:
    """Run every check on ``plan``; needs only the plan and its URDF.

    Args:
        plan: the plan (for example from :meth:`Plan.load`).
        robot: the loaded robot, to skip reloading the URDF.
        replay_steps: RK4 steps of the forward-dynamics replay (times 4, then 16, when the
            replay misses by more than half a tolerance: a fast motion needs finer steps).
        constraints: path constraints to check densely; default joint position and velocity
            limits.
    """
    constraints = default_constraints() if constraints is None else constraints
    robot = robot or _robot_for(plan)
    mmap = MomentumMap(robot)
    model, data = robot.model, robot.model.createData()
    samples = plan.samples
    duration = plan.duration
    coeffs = _polys(plan)

    # Momentum and CM along the samples.
    momentum_max = momentum_scale = cm_max = 0.0
    for q, qd, pos, quat, omega in zip(
        samples.q,
        samples.qd,
        samples.base_position,
        samples.base_quaternion_xyzw,
        samples.base_angular_velocity,
        strict=True,
    ):
        joints, rates = np.array(q), np.array(qd)
        config = robot.configuration(joints, pos, quat)
        cm_max = max(cm_max, float(np.linalg.norm(pin.centerOfMass(model, data, config))))
        linear = mmap.base_twist_map(joints)[:3] @ rates
        v = np.concatenate([linear, omega, rates])
        ag = pin.computeCentroidalMap(model, data, config)
        momentum_max = max(momentum_max, float(np.linalg.norm(ag @ v)))
        momentum_scale = max(momentum_scale, float(np.linalg.norm(ag[:, 6:] @ rates)))

    # Torques' base wrench, recomputed.
    wrench_max = torque_scale = 0.0
    for q, qd, qdd in zip(samples.q, samples.qd, samples.qdd, strict=True):
        dyn = inverse_dynamics(mmap, np.array(q), np.array(qd), np.array(qdd))
        wrench_max = max(wrench_max, float(np.abs(dyn.base_wrench).max()))
        torque_scale = max(torque_scale, float(np.abs(dyn.tau).max()))

    # Independent attitude integration (adaptive, in seconds).
    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        q, qd, _ = _state(coeffs, t)
        omega = mmap.f1(q) @ qd
        return 0.5 * quat_multiply(y, np.concatenate([omega, [0.0]]))

    start_quat = np.asarray(plan.base.start_quaternion_xyzw, dtype=float)
    target = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)
    sol = solve_ivp(rhs, (0.0, duration), start_quat, method="DOP853", rtol=1e-12, atol=1e-13)
    end = sol.y[:, -1] / np.linalg.norm(sol.y[:, -1])
    attitude_independent = geodesic_angle(end, target)

    # Forward-dynamics replay from the start at rest.
    start = np.asarray(plan.request.start_joints, dtype=float)
    goal = np.asarray(plan.request.goal_joints, dtype=float)
    torque = joint_torque_function(plan, mmap)
    # RK4 at a fixed count; a fast motion gets four (then sixteen) times the steps before its
    # replay error is held against the plan (a count, so every machine decides alike).
    for refine in range(3):
        result = replay(mmap, start, start_quat, torque, duration, replay_steps * 4**refine)
        joint_error = float(np.abs(_wrap_joints(robot, result.joints - goal)).max())
        attitude_error = geodesic_angle(result.quaternion_xyzw, target)
        if (
            joint_error <= 0.5 * TOLERANCES["replay_joint"]
            and attitude_error <= 0.5 * TOLERANCES["replay_attitude_rad"]
        ):
            break
    replay_report = {
        "attitude_error_rad": attitude_error,
        "joint_error": joint_error,
        "final_rate_max": float(np.abs(result.rates).max()),
        "momentum_drift": result.momentum_max,
        "steps": float(result.steps),
    }

    boundary = boundary_errors(coeffs[0], start, goal, duration)
    travel = np.maximum(1.0, np.abs(goal - start))

    # The samples are the polynomials, sampled.
    worst = 0.0
    for t, q, qd, qdd in zip(samples.t, samples.q, samples.qd, samples.qdd, strict=True):
        exact = _state(coeffs, t)
        for got, want, power in ((q, exact[0], 0), (qd, exact[1], 1), (qdd, exact[2], 2)):
            error = np.abs(np.asarray(got) - want) * duration**power / travel
            worst = max(worst, float(error.max()))

    tol = TOLERANCES
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
        Check("attitude_independent", attitude_independent, tol["attitude_independent_rad"], "rad"),
        Check(
            "replay_attitude",
            replay_report["attitude_error_rad"],
            tol["replay_attitude_rad"],
            "rad",
        ),
        Check("replay_joints", replay_report["joint_error"], tol["replay_joint"], "rad|m"),
        Check("boundary", boundary["relative_max"], tol["boundary_relative"], "1"),
        Check("samples", worst, tol["samples_relative"], "1"),
    ]
    path = JointPolynomials.from_lists([c.tolist() for c in coeffs[0]], duration)
    for constraint in constraints:
        if constraint.applies_to(robot):
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
    return Verification(tuple(checks))


def _wrap_joints(robot: Robot, delta: np.ndarray) -> np.ndarray:
    """Joint differences, continuous joints wrapped to (-pi, pi] (rad or m)."""
    out = np.array(delta, dtype=float)
    for i, joint in enumerate(robot.joints):
        if joint.kind == "continuous":
            out[i] = math.remainder(out[i], 2.0 * math.pi)
    return out

"""Joint torques and forward-dynamics replay of the free-floating system.

Along a zero-momentum motion the centroidal momentum stays zero, so its rate does too:
``A_g a + dA_g v = 0``. Splitting ``a = [a_base; qddot]`` gives the base acceleration the joint
motion implies, and Pinocchio's inverse dynamics (RNEA) of the whole free-floating system with
that acceleration gives the joint torques of the reduced dynamics ``H qddot + C = tau`` (N m,
or N for prismatic joints). The six base entries of the RNEA result are the wrench the base
would need: zero up to rounding, a consistency check of its own. Gravity is zero.

The replay runs Pinocchio's articulated-body algorithm (ABA) on the full system, base free,
driven only by the joint torques, with a fixed-step fourth-order Runge-Kutta scheme whose
configuration updates use ``pin.integrate`` on the configuration manifold.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .momentum import MomentumMap

__all__ = ["InverseDynamics", "ReplayResult", "inverse_dynamics", "replay"]


@dataclass(frozen=True)
class InverseDynamics:
    """Inverse dynamics at one instant.

    Attributes:
        tau: N joint torques (N m, or N for prismatic joints).
        base_wrench: the 6 base entries of the RNEA result (N, N m): ~0 for a consistent motion.
        base_acceleration: base spatial acceleration (m/s^2, rad/s^2; base frame).
    """

    tau: np.ndarray
    base_wrench: np.ndarray
    base_acceleration: np.ndarray


def inverse_dynamics(
    mmap: MomentumMap,
    joints: np.ndarray,
    rates: np.ndarray,
    accelerations: np.ndarray,
    quaternion_xyzw: np.ndarray | None = None,
) -> InverseDynamics:
    """Joint torques of a zero-momentum motion at one instant.

    Args:
        mmap: momentum map of the robot.
        joints: N joint values (rad or m).
        rates: N joint rates (rad/s or m/s).
        accelerations: N joint accelerations (rad/s^2 or m/s^2).
        quaternion_xyzw: base attitude; the torques do not depend on it (no gravity), default
            identity.
    """
    model, data = mmap.model, mmap.data
    quat = np.array([0.0, 0.0, 0.0, 1.0]) if quaternion_xyzw is None else quaternion_xyzw
    q = mmap.configuration(np.asarray(joints, float), quat)
    v = mmap.velocity(np.asarray(joints, float), np.asarray(rates, float))
    d_ag = pin.computeCentroidalMapTimeVariation(model, data, q, v)
    ag = data.Ag
    rhs = ag[:, 6:] @ accelerations + d_ag @ v
    a_base = -np.linalg.solve(ag[:, :6], rhs)
    a = np.concatenate([a_base, accelerations])
    full = pin.rnea(model, data, q, v, a)
    return InverseDynamics(
        tau=full[6:].copy(), base_wrench=full[:6].copy(), base_acceleration=a_base
    )


@dataclass(frozen=True)
class ReplayResult:
    """Final state of a forward-dynamics replay.

    Attributes:
        joints: N final joint values (rad or m).
        rates: N final joint rates (rad/s or m/s).
        quaternion_xyzw: final base attitude.
        momentum_max: largest total momentum norm met along the replay (kg m/s, kg m^2/s).
        steps: number of RK4 steps taken.
    """

    joints: np.ndarray
    rates: np.ndarray
    quaternion_xyzw: np.ndarray
    momentum_max: float
    steps: int


def replay(
    mmap: MomentumMap,
    start_joints: np.ndarray,
    start_quaternion_xyzw: np.ndarray,
    torque: Callable[[float], np.ndarray],
    duration: float,
    steps: int = 2000,
) -> ReplayResult:
    """Simulate the free-floating system from rest under the joint torques ``torque(t)``.

    Args:
        mmap: momentum map of the robot (its model and data are used).
        start_joints: N joint values at t = 0 (rad or m); the system starts at rest with its CM
            at the origin.
        start_quaternion_xyzw: base attitude at t = 0.
        torque: joint torques (N m or N) as a function of time (s).
        duration: simulated time (s).
        steps: number of fixed RK4 steps.
    """
    model, data = mmap.model, mmap.model.createData()
    q = mmap.configuration(np.asarray(start_joints, float), np.asarray(start_quaternion_xyzw))
    v = np.zeros(model.nv)
    dt = duration / steps
    base = np.zeros(6)

    def accel(q_: np.ndarray, v_: np.ndarray, t: float) -> np.ndarray:
        return pin.aba(model, data, q_, v_, np.concatenate([base, torque(t)]))

    momentum_max = 0.0
    t = 0.0
    for _ in range(steps):
        a1 = accel(q, v, t)
        v2 = v + 0.5 * dt * a1
        a2 = accel(pin.integrate(model, q, 0.5 * dt * v), v2, t + 0.5 * dt)
        v3 = v + 0.5 * dt * a2
        a3 = accel(pin.integrate(model, q, 0.5 * dt * v2), v3, t + 0.5 * dt)
        v4 = v + dt * a3
        a4 = accel(pin.integrate(model, q, dt * v3), v4, t + dt)
        q = pin.integrate(model, q, dt / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4))
        v = v + dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        t += dt
        momentum_max = max(momentum_max, float(np.linalg.norm(mmap.momentum(q, v))))
    joints = mmap.robot.joint_values(q)
    rates = np.array([v[j.idx_v] for j in mmap.robot.joints])
    return ReplayResult(
        joints=joints,
        rates=rates,
        quaternion_xyzw=q[3:7].copy(),
        momentum_max=momentum_max,
        steps=steps,
    )

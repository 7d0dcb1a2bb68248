"""Joint torques and forward-dynamics replay of the free-floating system.

Along a zero-momentum motion the centroidal momentum stays zero, so its rate does too:
``A_g a + dA_g v = 0``. Splitting ``a = [a_base; qddot]`` gives the base acceleration the joint
motion implies, and Pinocchio's inverse dynamics (RNEA) of the whole free-floating system with
that acceleration gives the joint torques of the reduced dynamics ``H qddot + C = tau`` (N m,
or N for prismatic joints). The six base entries of the RNEA result are the wrench the base
would need: zero up to rounding, a consistency check of its own. Gravity is zero.

The replay runs Pinocchio's articulated-body algorithm (ABA) on the full system, base free,
driven only by the joint torques, with a fixed-step fourth-order Runge-Kutta scheme whose
configuration is integrated as a vector in R^nq: the base position, the base quaternion (its
rate ``q (x) [omega, 0] / 2``) and the (cos, sin) pairs of continuous joints, renormalised after
every stage. Classical RK4 keeps its fourth order that way; chaining ``pin.integrate`` over the
stages' velocities would drop the base attitude to second order. The torques come
either from a function of time or from a table at the half-step instants ``k dt / 2``, which
lets a caller compute them in one batch (:func:`inverse_dynamics_batch`) and reuse them when it
doubles the steps to estimate the replay's own error.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np
import pinocchio as pin

from ..robot.model import Robot
from .momentum import MomentumMap

__all__ = [
    "InverseDynamics",
    "InverseDynamicsBatch",
    "ReplayResult",
    "inverse_dynamics",
    "inverse_dynamics_batch",
    "replay",
]


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
class InverseDynamicsBatch:
    """Inverse dynamics at K instants (see :func:`inverse_dynamics_batch`).

    Attributes:
        tau: (K, N) joint torques (N m, or N for prismatic joints).
        base_wrench: (K, 6) base entries of the RNEA result (N, N m): ~0 for a consistent motion.
        base_twist: (K, 6) zero-momentum base twist (m/s, rad/s; base frame).
        com: (K, 3) system CM in the base frame, base at the origin (m).
        end_effector: (K, 3) end-effector position in the base frame, base at the origin (m).
        end_effectors: (E, K, 3) the same for each of the robot's E end effectors (the first
            is ``end_effector``).
    """

    tau: np.ndarray
    base_wrench: np.ndarray
    base_twist: np.ndarray
    com: np.ndarray
    end_effector: np.ndarray
    end_effectors: np.ndarray


def inverse_dynamics_batch(
    mmap: MomentumMap, joints: np.ndarray, rates: np.ndarray, accelerations: np.ndarray
) -> InverseDynamicsBatch:
    """Joint torques of a zero-momentum motion at K instants, with the kinematics they need.

    The motion is evaluated with the base at the origin and identity attitude: without gravity
    the torques do not depend on the base pose, and the CM and end effector of any other base
    pose follow by one rotation and translation. Three Pinocchio calls per instant, no other
    per-instant Python work. The last batch per robot is kept: asked again for the very same
    instants (a plan's samples, by sampling then by its check), it is returned again (copies).

    Args:
        mmap: momentum map of the robot.
        joints: (K, N) joint values (rad or m).
        rates: (K, N) joint rates (rad/s or m/s).
        accelerations: (K, N) joint accelerations (rad/s^2 or m/s^2).
    """
    joints = np.atleast_2d(np.asarray(joints, dtype=float))
    rates = np.atleast_2d(np.asarray(rates, dtype=float))
    accelerations = np.atleast_2d(np.asarray(accelerations, dtype=float))
    key = b"".join(
        np.asarray(a.shape, dtype=np.int64).tobytes() + np.ascontiguousarray(a).tobytes()
        for a in (joints, rates, accelerations)
    )
    kept = _LAST_BATCH.get(mmap.robot)
    if kept is None or kept[0] != key:
        kept = (key, _inverse_dynamics_batch(mmap, joints, rates, accelerations))
        _LAST_BATCH[mmap.robot] = kept
    return InverseDynamicsBatch(*(np.array(a) for a in _arrays(kept[1])))


def _arrays(batch: InverseDynamicsBatch) -> tuple[np.ndarray, ...]:
    """The batch's arrays in field order (not copied)."""
    return tuple(getattr(batch, f.name) for f in fields(batch))


#: The last batch per robot: sampling and verification ask for the same samples' dynamics.
_LAST_BATCH: weakref.WeakKeyDictionary[Robot, tuple[bytes, InverseDynamicsBatch]] = (
    weakref.WeakKeyDictionary()
)


def _inverse_dynamics_batch(
    mmap: MomentumMap, joints: np.ndarray, rates: np.ndarray, accelerations: np.ndarray
) -> InverseDynamicsBatch:
    model, data = mmap.model, mmap.data
    configs = mmap.configurations(joints)
    k_count, nv = len(configs), model.nv
    ag = np.empty((k_count, 6, nv))
    com = np.empty((k_count, 3))
    for k in range(k_count):
        ag[k] = pin.computeCentroidalMap(model, data, configs[k])
        com[k] = data.com[0]
    twist = -np.linalg.solve(ag[:, :, :6], np.einsum("kij,kj->ki", ag[:, :, 6:], rates)[..., None])
    twist = twist[..., 0]
    v = np.concatenate([twist, rates], axis=1)
    d_ag = np.empty((k_count, 6, nv))
    frames = mmap.robot.end_effector_frames
    ee = np.empty((len(frames), k_count, 3))
    for k in range(k_count):
        d_ag[k] = pin.computeCentroidalMapTimeVariation(model, data, configs[k], v[k])
        for e, frame in enumerate(frames):
            ee[e, k] = pin.updateFramePlacement(model, data, frame).translation
    rhs = np.einsum("kij,kj->ki", ag[:, :, 6:], accelerations) + np.einsum("kij,kj->ki", d_ag, v)
    a_base = -np.linalg.solve(ag[:, :, :6], rhs[..., None])[..., 0]
    a = np.concatenate([a_base, accelerations], axis=1)
    full = np.empty((k_count, nv))
    for k in range(k_count):
        full[k] = pin.rnea(model, data, configs[k], v[k], a[k])
    mmap.evaluations += k_count
    return InverseDynamicsBatch(
        tau=full[:, 6:],
        base_wrench=full[:, :6],
        base_twist=twist,
        com=com,
        end_effector=ee[0],
        end_effectors=ee,
    )


class _Embedded:
    """``dq/dt`` of the embedded configuration from the velocity, and the projection back.

    The root joint is Pinocchio's free flyer: position (m) with rate ``R v_linear``, quaternion
    ``[x, y, z, w]`` with rate ``q (x) [omega, 0] / 2`` (``v`` in the base frame). A continuous
    joint's ``(cos, sin)`` turns at its rate; other joints' values move at their rates.
    Configurations are lists of plain floats (the replay's steps do a few dozen operations on
    a dozen numbers: cheaper than numpy's per-call cost); every operation is the one numpy
    would do element-wise, so results are the same to the bit.
    """

    def __init__(self, mmap: MomentumMap) -> None:
        joints = mmap.robot.joints
        self.nq = mmap.model.nq
        #: (q index, v index) of joints whose value moves at their rate.
        self.plain = [(j.idx_q, j.idx_v) for j in joints if j.kind != "continuous"]
        #: (cos index, v index) of continuous joints (their sin follows the cos).
        self.turning = [(j.idx_q, j.idx_v) for j in joints if j.kind == "continuous"]

    def rate(self, q: list[float], v: list[float]) -> list[float]:
        """``dq/dt`` at configuration ``q`` and velocity ``v`` (plain floats)."""
        x, y, z, w = q[3:7]
        vx, vy, vz, wx, wy, wz = v[:6]
        # R v_linear, with R of the quaternion
        tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)
        out = [
            vx + w * tx + y * tz - z * ty,
            vy + w * ty + z * tx - x * tz,
            vz + w * tz + x * ty - y * tx,
            0.5 * (w * wx + y * wz - z * wy),
            0.5 * (w * wy + z * wx - x * wz),
            0.5 * (w * wz + x * wy - y * wx),
            -0.5 * (x * wx + y * wy + z * wz),
        ]
        out.extend([0.0] * (self.nq - 7))
        for iq, iv in self.plain:
            out[iq] = v[iv]
        for iq, iv in self.turning:
            out[iq] = -q[iq + 1] * v[iv]
            out[iq + 1] = q[iq] * v[iv]
        return out

    def project(self, q: list[float]) -> list[float]:
        """Unit quaternion and unit (cos, sin) pairs again, in place."""
        x, y, z, w = q[3:7]
        norm = math.sqrt(x * x + y * y + z * z + w * w) or math.nan  # nan, as numpy's 0 / 0
        q[3:7] = x / norm, y / norm, z / norm, w / norm
        for iq, _ in self.turning:
            c, s = q[iq], q[iq + 1]
            n = float(np.hypot(c, s)) or math.nan  # numpy's hypot, as the array form used
            q[iq], q[iq + 1] = c / n, s / n
        return q

    def stage(self, q: list[float], h: float, r: list[float]) -> list[float]:
        """``project(q + h r)``."""
        return self.project([a + h * b for a, b in zip(q, r, strict=True)])

    def step(self, q: list[float], dt: float, rates: tuple[list[float], ...]) -> list[float]:
        """RK4's combination ``project(q + dt / 6 (r1 + 2 r2 + 2 r3 + r4))``."""
        sixth = dt / 6.0
        r1, r2, r3, r4 = rates
        return self.project(
            [
                a + sixth * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
                for a, b1, b2, b3, b4 in zip(q, r1, r2, r3, r4, strict=True)
            ]
        )


@dataclass(frozen=True)
class ReplayResult:
    """Final state of a forward-dynamics replay.

    Attributes:
        joints: N final joint values (rad or m).
        rates: N final joint rates (rad/s or m/s).
        quaternion_xyzw: final base attitude.
        momentum_max: largest total momentum norm met along the replay (kg m/s, kg m^2/s);
            NaN unless asked for.
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
    torque: Callable[[float], np.ndarray] | np.ndarray,
    duration: float,
    steps: int = 2000,
    track_momentum: bool = True,
    nodes: np.ndarray | None = None,
) -> ReplayResult:
    """Simulate the free-floating system from rest under the joint torques ``torque(t)``.

    Args:
        mmap: momentum map of the robot (its model and data are used).
        start_joints: N joint values at t = 0 (rad or m); the system starts at rest with its CM
            at the origin.
        start_quaternion_xyzw: base attitude at t = 0.
        torque: joint torques (N m or N): a function of time (s), or a (2 steps + 1, N) table
            at the step ends and midpoints (``k duration / (2 steps)`` for uniform steps).
        duration: simulated time (s).
        steps: number of RK4 steps (>= 1).
        track_momentum: record the largest total momentum along the replay.
        nodes: the steps' ends, ``steps + 1`` ascending instants from 0 to ``duration`` (s);
            default uniform.
    """
    if steps < 1:
        raise ValueError(f"the replay needs at least one step, got {steps}")
    model, data = mmap.model, mmap.model.createData()
    q = mmap.configuration(np.asarray(start_joints, float), np.asarray(start_quaternion_xyzw))
    v = np.zeros(model.nv)
    ends = np.linspace(0.0, duration, steps + 1) if nodes is None else np.asarray(nodes, float)
    if ends.shape != (steps + 1,):
        raise ValueError(f"{len(ends)} step ends for {steps} steps")
    times = np.empty(2 * steps + 1)
    times[0::2], times[1::2] = ends, 0.5 * (ends[:-1] + ends[1:])
    widths = np.diff(ends)
    n = mmap.robot.n
    if callable(torque):
        table = np.array([torque(float(t)) for t in times])
    else:
        table = np.asarray(torque, dtype=float)
        if table.shape != (2 * steps + 1, n):
            raise ValueError(f"torque table of shape {table.shape}, need {(2 * steps + 1, n)}")
    forces = np.zeros((len(table), model.nv))
    forces[:, [j.idx_v for j in mmap.robot.joints]] = table
    aba = pin.aba

    embedded = _Embedded(mmap)
    rate, stage, array = embedded.rate, embedded.stage, np.array
    momentum_max = 0.0 if track_momentum else math.nan
    x = q.tolist()
    # A step too long for the motion can blow up; the caller sees non-finite results.
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(steps):
            dt = float(widths[k])
            half = 0.5 * dt
            f0, fh, f1 = forces[2 * k], forces[2 * k + 1], forces[2 * k + 2]
            a1, r1 = aba(model, data, array(x), v, f0), rate(x, v.tolist())
            x2, v2 = stage(x, half, r1), v + half * a1
            a2, r2 = aba(model, data, array(x2), v2, fh), rate(x2, v2.tolist())
            x3, v3 = stage(x, half, r2), v + half * a2
            a3, r3 = aba(model, data, array(x3), v3, fh), rate(x3, v3.tolist())
            x4, v4 = stage(x, dt, r3), v + dt * a3
            a4, r4 = aba(model, data, array(x4), v4, f1), rate(x4, v4.tolist())
            x = embedded.step(x, dt, (r1, r2, r3, r4))
            v = v + dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
            if track_momentum:
                momentum_max = max(momentum_max, float(np.linalg.norm(mmap.momentum(array(x), v))))
    q = array(x)
    joints = mmap.robot.joint_values(q)
    rates = np.array([v[j.idx_v] for j in mmap.robot.joints])
    return ReplayResult(
        joints=joints,
        rates=rates,
        quaternion_xyzw=q[3:7].copy(),
        momentum_max=momentum_max,
        steps=steps,
    )

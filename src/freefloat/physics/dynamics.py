"""Joint torques and forward-dynamics replay of the free-floating system.

Along a zero-momentum motion the centroidal momentum stays zero, so its rate does too:
``A_g a + dA_g v = 0``. Splitting ``a = [a_base; qddot]`` gives the base acceleration the joint
motion implies, and Pinocchio's inverse dynamics (RNEA) of the whole free-floating system with
that acceleration gives the joint torques of the reduced dynamics ``H qddot + C = tau`` (N m,
or N for prismatic joints). The six base entries of the RNEA result are the wrench the base
would need: zero up to rounding, a consistency check of its own. Gravity is zero.

The replay runs Pinocchio's articulated-body algorithm (ABA) on the full system, base free,
driven only by the joint torques, with the classical fourth-order Runge-Kutta scheme on the
whole state: the joint values (continuous joints as angles), the velocity ``[v_base; qdot]``
(base twist in the base frame) and the base quaternion (its rate ``q (x) [omega, 0] / 2``).
Without gravity ABA does not depend on the base pose (velocities are in the base frame), so the
joint values and velocity are integrated first with the base held at the identity, and the
quaternion, whose rate is linear in it, follows from the same RK4 stages afterwards as a
product of one 4 x 4 step matrix per step (normalised once at the end: the linear map only
scales it between steps). The base position enters nothing the replay reports and is not
integrated. The torques come either from a function of time or from a table at the half-step
instants ``k dt / 2``, which lets a caller compute them in one batch
(:func:`inverse_dynamics_batch`) and reuse them when it doubles the steps to estimate the
replay's own error.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np
import pinocchio as pin

from ..robot.model import Robot
from .attitude import ordered_product, quat_rate_matrices
from .momentum import MomentumMap

__all__ = [
    "InverseDynamics",
    "InverseDynamicsBatch",
    "ReplayResult",
    "centre_of_mass",
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
    pose follow by one rotation and translation. Three Pinocchio calls per instant and one per
    end effector (the CM comes with the centroidal maps: :func:`centre_of_mass`). The last
    batch per robot is kept: asked again for the very same instants (a plan's samples, by
    sampling then by its check), it is returned again (copies).

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


#: Classical RK4's weights of its four stage slopes (times the step over 6).
_RK4_WEIGHTS = np.array([1.0, 2.0, 2.0, 1.0])

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
    cmap, dmap, place, rnea = (
        pin.computeCentroidalMap,
        pin.computeCentroidalMapTimeVariation,
        pin.updateFramePlacement,
        pin.rnea,
    )
    ag = np.array([cmap(model, data, q) for q in configs]).reshape(k_count, 6, nv)
    twist = -np.linalg.solve(ag[:, :, :6], np.einsum("kij,kj->ki", ag[:, :, 6:], rates)[..., None])
    twist = twist[..., 0]
    v = np.concatenate([twist, rates], axis=1)
    d_ag = np.empty((k_count, 6, nv))
    frames = mmap.robot.end_effector_frames
    ee = np.empty((len(frames), k_count, 3))
    for q, velocity, slot, *positions in zip(configs, v, d_ag, *ee, strict=True):
        slot[...] = dmap(model, data, q, velocity)  # also places the joints
        for position, frame in zip(positions, frames, strict=True):
            position[...] = place(model, data, frame).translation
    rhs = np.einsum("kij,kj->ki", ag[:, :, 6:], accelerations) + np.einsum("kij,kj->ki", d_ag, v)
    a_base = -np.linalg.solve(ag[:, :, :6], rhs[..., None])[..., 0]
    a = np.concatenate([a_base, accelerations], axis=1)
    full = np.array([rnea(model, data, *qva) for qva in zip(configs, v, a, strict=True)])
    full = full.reshape(k_count, nv)
    mmap.evaluations += k_count
    return InverseDynamicsBatch(
        tau=full[:, 6:],
        base_wrench=full[:, :6],
        base_twist=twist,
        com=centre_of_mass(ag),
        end_effector=ee[0],
        end_effectors=ee,
    )


def centre_of_mass(ag: np.ndarray) -> np.ndarray:
    """(K, 3) system CM relative to the base origin (m) from K centroidal maps (K, 6, nv).

    The base twist's share of the linear momentum is ``m R v - m [c - p]x R omega`` (``R``
    the base rotation, ``m`` the mass in kg, ``c`` the CM and ``p`` the base origin, both in
    the frame of the maps): ``ag[:, 0:3, 0:3] = m R`` and ``ag[:, 0:3, 3:6] = -m [c - p]x R``,
    so ``-[c - p]x = ag[:, 0:3, 3:6] ag[:, 0:3, 0:3]^T / m^2``. No Pinocchio call: the CM
    comes with the maps.
    """
    linear = ag[:, 0:3, 0:6]
    mass = ag[:, 0, 0:3]
    cross = linear[:, :, 3:6] @ np.swapaxes(linear[:, :, 0:3], 1, 2)
    cross /= np.einsum("ki,ki->k", mass, mass)[:, None, None]  # m^2: the first row of m R
    return np.stack([cross[:, 1, 2], cross[:, 2, 0], cross[:, 0, 1]], axis=1)


class _Configurations:
    """Pinocchio configurations from joint values, the base at the origin with identity attitude.

    Continuous joints take their (cos, sin) pair; other joints their value (rad or m). One
    buffer is filled and returned each call (ABA reads it at once).
    """

    def __init__(self, mmap: MomentumMap) -> None:
        joints = mmap.robot.joints
        self.q = pin.neutral(mmap.model)
        self.q[0:7] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]
        #: (joint, q index) of joints stored as their value, and of continuous joints
        self.plain = [(i, j.idx_q) for i, j in enumerate(joints) if j.kind != "continuous"]
        self.turning = [(i, j.idx_q) for i, j in enumerate(joints) if j.kind == "continuous"]
        #: all joints plain, stored in order from index 7: one slice assignment
        self.contiguous = not self.turning and [q for _, q in self.plain] == list(
            range(7, 7 + len(self.plain))
        )

    def __call__(self, values: np.ndarray) -> np.ndarray:
        """The configuration of N joint values (rad or m)."""
        q = self.q
        if self.contiguous:
            q[7:] = values
            return q
        listed = values.tolist()  # a dozen entries: cheaper one by one than by numpy indexing
        for i, iq in self.plain:
            q[iq] = listed[i]
        for i, iq in self.turning:
            value = listed[i]
            if math.isinf(value):  # a replay that blew up: NaN, as numpy gives (math raises)
                value = math.nan
            q[iq], q[iq + 1] = math.cos(value), math.sin(value)
        return q


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
    ends = np.linspace(0.0, duration, steps + 1) if nodes is None else np.asarray(nodes, float)
    if ends.shape != (steps + 1,):
        raise ValueError(f"{len(ends)} step ends for {steps} steps")
    times = np.empty(2 * steps + 1)
    times[0::2], times[1::2] = ends, 0.5 * (ends[:-1] + ends[1:])
    widths = np.diff(ends)
    robot = mmap.robot
    rate_index = np.array([j.idx_v for j in robot.joints], dtype=int)
    forces = _generalised_forces(mmap, torque, times, rate_index)
    n, config, aba = robot.n, _Configurations(mmap), pin.aba
    # The state y = [joint values (N); velocity (nv)], its rate [joint rates; ABA]; every
    # stage's state is kept (the base angular rate) and each stage's rate written in place.
    rates_of_y: slice | np.ndarray = n + rate_index
    if rate_index.tolist() == list(range(6, model.nv)):
        rates_of_y = slice(n + 6, n + model.nv)  # a view, not a copy
    states = np.empty((steps, 4, n + model.nv))
    slopes = np.empty((4, n + model.nv))
    y = np.concatenate([np.asarray(start_joints, dtype=float), np.zeros(model.nv)])
    momentum_max = 0.0 if track_momentum else math.nan
    # A step too long for the motion can blow up; the caller sees non-finite results.
    with np.errstate(over="ignore", invalid="ignore"):
        for k, dt in enumerate(widths.tolist()):
            stage, f0, fh = states[k], forces[2 * k], forces[2 * k + 1]
            stage[0] = y
            for i, (width, force) in enumerate(((0.5 * dt, f0), (0.5 * dt, fh), (dt, fh))):
                here, slope = stage[i], slopes[i]
                slope[:n] = here[rates_of_y]
                slope[n:] = aba(model, data, config(here[:n]), here[n:], force)
                np.multiply(slope, width, out=stage[i + 1])
                stage[i + 1] += y
            here, slope = stage[3], slopes[3]
            slope[:n] = here[rates_of_y]
            slope[n:] = aba(model, data, config(here[:n]), here[n:], forces[2 * k + 2])
            y = y + (dt / 6.0 * _RK4_WEIGHTS) @ slopes
            if track_momentum:
                momentum = mmap.momentum(config(y[:n]), y[n:])
                momentum_max = max(momentum_max, float(np.linalg.norm(momentum)))
    stage_omega = states[:, :, n + 3 : n + 6]
    with np.errstate(over="ignore", invalid="ignore"):  # a blown-up replay: non-finite, quietly
        quaternion = _rk4_quaternion(np.asarray(start_quaternion_xyzw, float), stage_omega, widths)
    return ReplayResult(
        joints=robot.joint_values(config(y[:n])),
        rates=y[n:][rate_index].copy(),
        quaternion_xyzw=quaternion,
        momentum_max=momentum_max,
        steps=steps,
    )


def _generalised_forces(
    mmap: MomentumMap,
    torque: Callable[[float], np.ndarray] | np.ndarray,
    times: np.ndarray,
    rate_index: np.ndarray,
) -> np.ndarray:
    """(len(times), nv) generalised forces of :func:`replay`'s ``torque`` at ``times`` (s).

    The joint torques (N m or N) in the joints' velocity slots, zero on the base.
    """
    if callable(torque):
        table = np.array([torque(float(t)) for t in times])
    else:
        table = np.asarray(torque, dtype=float)
        if table.shape != (len(times), mmap.robot.n):
            raise ValueError(
                f"torque table of shape {table.shape}, need {(len(times), mmap.robot.n)}"
            )
    forces = np.zeros((len(table), mmap.model.nv))
    forces[:, rate_index] = table
    return forces


def _rk4_quaternion(start: np.ndarray, stage_omega: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Final attitude of ``y' = 0.5 y (x) [omega, 0]`` by RK4 given each stage's ``omega``.

    Classical RK4 on this linear equation makes every step a 4 x 4 matrix, built in one batch
    from the stages' angular velocities (M, 4, 3; rad/s) and the step widths (M; s).
    """
    a = quat_rate_matrices(stage_omega)
    h = widths[:, None, None]
    k1 = a[:, 0]
    k2 = a[:, 1] + 0.5 * h * (a[:, 1] @ k1)
    k3 = a[:, 2] + 0.5 * h * (a[:, 2] @ k2)
    k4 = a[:, 3] + h * (a[:, 3] @ k3)
    phi = np.eye(4) + h / 6.0 * (k1 + 2.0 * (k2 + k3) + k4)
    end = ordered_product(phi) @ start
    return end / np.linalg.norm(end)

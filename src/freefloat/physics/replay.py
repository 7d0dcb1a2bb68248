"""Forward-dynamics replay of the free-floating system under given joint torques.

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
instants ``k dt / 2``, which lets a caller compute them in one batch and reuse them when it
doubles the steps to estimate the replay's own error.

The joint values' rate is the joints' share of the velocity, so each RK4 stage is written in
its second-order form: the stage's joint values ``x + w v_i[joints]`` and velocity
``v + w a_i`` (``w`` the stage's width), with one ABA call per stage and the stage velocities
kept for the quaternion.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .attitude import ordered_product, quat_rate_matrices
from .momentum import MomentumMap

__all__ = ["ReplayResult", "replay"]

#: Classical RK4's weights of its four stage slopes (times the step over 6).
_RK4_WEIGHTS = np.array([1.0, 2.0, 2.0, 1.0])


class _Configurations:
    """Pinocchio configurations from joint values, the base at the origin with identity attitude.

    One configuration vector is kept and overwritten: each call returns the same array.
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

    def stage(self, x: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
        """``place(w, rates)``: the configuration of the joint values ``x + w rates`` (rad or m).

        ``x`` (N,) is read at each call (the caller updates it in place). All joints plain and
        in order: written straight into the configuration, no intermediate array.
        """
        if self.contiguous:
            joints = self.q[7:]

            def place(width: float, rates: np.ndarray) -> np.ndarray:
                np.multiply(rates, width, out=joints)
                joints.__iadd__(x)  # in place: ``joints += x`` would rebind the closure's name
                return self.q

            return place
        return lambda width, rates: self(rates * width + x)


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
        mmap: momentum map of the robot (its model is used, with data of its own).
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
    ends = np.linspace(0.0, duration, steps + 1) if nodes is None else np.asarray(nodes, float)
    if ends.shape != (steps + 1,):
        raise ValueError(f"{len(ends)} step ends for {steps} steps")
    times = np.empty(2 * steps + 1)
    times[0::2], times[1::2] = ends, 0.5 * (ends[:-1] + ends[1:])
    widths = np.diff(ends)
    robot = mmap.robot
    rate_index = np.array([j.idx_v for j in robot.joints], dtype=int)
    forces = _generalised_forces(mmap, torque, times, rate_index)
    config = _Configurations(mmap)
    x = np.array(start_joints, dtype=float)
    # A step too long for the motion can blow up; the caller sees non-finite results.
    with np.errstate(over="ignore", invalid="ignore"):
        stages, v, momentum_max = _rk4(mmap, config, x, forces, widths, rate_index, track_momentum)
        quaternion = _rk4_quaternion(
            np.asarray(start_quaternion_xyzw, float), stages[:, :, 3:6], widths
        )
    return ReplayResult(
        joints=robot.joint_values(config(x)),
        rates=v[rate_index].copy(),
        quaternion_xyzw=quaternion,
        momentum_max=momentum_max,
        steps=steps,
    )


def _rk4(
    mmap: MomentumMap,
    config: _Configurations,
    x: np.ndarray,
    forces: np.ndarray,
    widths: np.ndarray,
    rate_index: np.ndarray,
    track_momentum: bool,
) -> tuple[np.ndarray, np.ndarray, float]:
    """RK4 steps of the joints and velocity from rest: (steps, 4, nv) stage velocities.

    ``x`` (N joint values, rad or m) is advanced in place; returns the stages' velocities
    (base twist in the base frame, joint rates), the final velocity and the largest momentum
    norm met (NaN unless ``track_momentum``). ``forces``: generalised forces at the step ends
    and midpoints (N m or N).
    """
    model = mmap.model
    data, aba = model.createData(), pin.aba
    place = config.stage(x)
    joint_rates: slice | np.ndarray = rate_index
    if rate_index.tolist() == list(range(6, model.nv)):
        joint_rates = slice(6, model.nv)  # a view, not a copy
    stages = np.empty((len(widths), 4, model.nv))
    accelerations = np.empty((4, model.nv))
    v = np.zeros(model.nv)
    a0, a1, a2, a3 = accelerations  # views, each stage's written in place
    momentum_max = 0.0 if track_momentum else math.nan
    for k, dt in enumerate(widths.tolist()):
        half = 0.5 * dt
        v0, v1, v2, v3 = stages[k]
        f0, fh, f1 = forces[2 * k], forces[2 * k + 1], forces[2 * k + 2]
        v0[...] = v
        a0[...] = aba(model, data, config(x), v, f0)
        np.multiply(a0, half, out=v1)
        v1 += v
        a1[...] = aba(model, data, place(half, v[joint_rates]), v1, fh)
        np.multiply(a1, half, out=v2)
        v2 += v
        a2[...] = aba(model, data, place(half, v1[joint_rates]), v2, fh)
        np.multiply(a2, dt, out=v3)
        v3 += v
        a3[...] = aba(model, data, place(dt, v2[joint_rates]), v3, f1)
        weights = dt / 6.0 * _RK4_WEIGHTS
        x += (weights @ stages[k])[joint_rates]
        v = v + weights @ accelerations
        if track_momentum:
            momentum = mmap.momentum(config(x), v)
            momentum_max = max(momentum_max, float(np.linalg.norm(momentum)))
    return stages, v, momentum_max


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

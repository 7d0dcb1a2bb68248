"""Forward-dynamics replay of the free-floating system under given joint torques.

The replay runs Pinocchio's articulated-body algorithm (ABA) on the full system, base free,
driven only by the joint torques, with Butcher's fifth-order Runge-Kutta method
(:mod:`freefloat.physics.runge_kutta`; six stages on the quarters of each step) on the whole
state: the joint values (continuous joints as angles), the velocity ``[v_base; qdot]`` (base
twist in the base frame) and the base quaternion (its rate ``q (x) [omega, 0] / 2``). Without
gravity ABA does not depend on the base pose (velocities are in the base frame), so the joint
values and velocity are integrated first with the base held at the identity, and the
quaternion, whose rate is linear in it, follows from the same stages afterwards as a product of
one 4 x 4 step matrix per step (normalised once at the end: the linear map only scales it
between steps). The base position enters nothing the replay reports and is not integrated.
The torques come either from a function of time or from a table at the quarter-step instants
``k dt / 4``, which lets a caller compute them in one batch and reuse them when it doubles the
steps to estimate the replay's own error.

The joint values' rate is the joints' share of the velocity, so each stage is written in its
second-order form: the stage's joint values ``x + h sum_j a_ij v_j[joints]`` and velocity
``v + h sum_j a_ij a_j`` (``a_j`` the stages' accelerations), with one ABA call per stage and
the stage velocities kept for the quaternion.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .attitude import ordered_product
from .momentum import MomentumMap
from .runge_kutta import QUARTERS, STAGE_MATRIX, WEIGHTS, step_matrices

__all__ = ["ReplayResult", "replay"]


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


@dataclass(frozen=True)
class ReplayResult:
    """Final state of a forward-dynamics replay.

    Attributes:
        joints: N final joint values (rad or m).
        rates: N final joint rates (rad/s or m/s).
        quaternion_xyzw: final base attitude.
        momentum_max: largest total momentum norm met along the replay (kg m/s, kg m^2/s);
            NaN unless asked for.
        steps: number of Runge-Kutta steps taken.
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
    start_velocity: np.ndarray | None = None,
) -> ReplayResult:
    """Simulate the free-floating system under the joint torques ``torque(t)``, from rest.

    Args:
        mmap: momentum map of the robot (its model is used, with data of its own).
        start_joints: N joint values at t = 0 (rad or m); the system starts at rest (or at
            ``start_velocity``) with its CM at the origin.
        start_quaternion_xyzw: base attitude at t = 0.
        torque: joint torques (N m or N): a function of time (s), or a (4 steps + 1, N) table
            at the quarters of the steps (``k duration / (4 steps)`` for uniform steps).
        duration: simulated time (s).
        steps: number of Runge-Kutta steps (>= 1).
        track_momentum: record the largest total momentum along the replay.
        nodes: the steps' ends, ``steps + 1`` ascending instants from 0 to ``duration`` (s);
            default uniform.
        start_velocity: the velocity at t = 0 instead of rest, ``[v_base; qdot]`` (the
            Pinocchio model's nv entries: base twist in the base frame, m/s and rad/s, then
            the joint rates in their velocity slots); a motion of zero momentum keeps it zero.
    """
    if steps < 1:
        raise ValueError(f"the replay needs at least one step, got {steps}")
    ends = np.linspace(0.0, duration, steps + 1) if nodes is None else np.asarray(nodes, float)
    if ends.shape != (steps + 1,):
        raise ValueError(f"{len(ends)} step ends for {steps} steps")
    widths = np.diff(ends)
    times = np.append(ends[:-1, None] + widths[:, None] * np.arange(4) / 4.0, ends[-1])
    robot = mmap.robot
    rate_index = np.array([j.idx_v for j in robot.joints], dtype=int)
    forces = _generalised_forces(mmap, torque, times, rate_index)
    config = _Configurations(mmap)
    x = np.array(start_joints, dtype=float)
    # A step too long for the motion can blow up; the caller sees non-finite results.
    with np.errstate(over="ignore", invalid="ignore"):
        stages, v, momentum_max = _stages(
            mmap, config, x, forces, widths, rate_index, track_momentum, start_velocity
        )
        end = ordered_product(step_matrices(stages[:, :, 3:6], widths))
        quaternion = end @ np.asarray(start_quaternion_xyzw, float)
        quaternion /= np.linalg.norm(quaternion)
    return ReplayResult(
        joints=robot.joint_values(config(x)),
        rates=v[rate_index].copy(),
        quaternion_xyzw=quaternion,
        momentum_max=momentum_max,
        steps=steps,
    )


def _stages(
    mmap: MomentumMap,
    config: _Configurations,
    x: np.ndarray,
    forces: np.ndarray,
    widths: np.ndarray,
    rate_index: np.ndarray,
    track_momentum: bool,
    start_velocity: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Runge-Kutta steps of the joints and velocity: (steps, 6, nv) stage velocities.

    From rest, or from ``start_velocity`` (nv entries, as :func:`replay` takes it).

    ``x`` (N joint values, rad or m) is advanced in place; returns the stages' velocities
    (base twist in the base frame, joint rates), the final velocity and the largest momentum
    norm met (NaN unless ``track_momentum``). ``forces``: generalised forces at the quarters of
    the steps (N m or N). Each stage's increments go into one kept buffer and, when the joints
    fill the configuration from index 7 in order, its joint values straight into the
    configuration: the same operations as ``x + increment``, without a new array per stage.
    """
    model, nv = mmap.model, mmap.model.nv
    data, aba = model.createData(), pin.aba
    joint_rates: slice | np.ndarray = rate_index
    if rate_index.tolist() == list(range(6, nv)):
        joint_rates = slice(6, nv)  # a view, not a copy
    count = len(WEIGHTS)
    stages = np.empty((len(widths), count, nv))
    # per stage [velocity; acceleration]: one product of a row of a_ij gives both increments
    slopes = np.empty((count, 2 * nv))
    velocities, accelerations = slopes[:, :nv], slopes[:, nv:]
    before = [slopes[:i] for i in range(count)]  # the stages before each one
    change = np.empty(2 * nv)  # a stage's increments of [joints and base; velocity]
    rate_change = change[nv:]
    # the joints' increments as a view of the buffer when their slots are contiguous
    moved = change[joint_rates] if isinstance(joint_rates, slice) else None
    here_q = config.q[7:] if config.contiguous and moved is not None else None
    table = list(forces)  # row views: cheaper to pick from a list than by numpy indexing
    rows = np.empty_like(STAGE_MATRIX)
    stage_rows = [rows[i, :i] for i in range(count)]
    v = np.zeros(nv) if start_velocity is None else np.array(start_velocity, dtype=float)
    momentum_max = 0.0 if track_momentum else math.nan
    for k, dt in enumerate(widths.tolist()):
        np.multiply(dt, STAGE_MATRIX, out=rows)
        velocities[0] = v
        accelerations[0] = aba(model, data, config(x), v, table[4 * k])
        for i in range(1, count):
            np.matmul(stage_rows[i], before[i], out=change)
            here = velocities[i]
            np.add(v, rate_change, out=here)
            if here_q is not None and moved is not None:  # here_q is set only with moved
                np.add(x, moved, out=here_q)
                q = config.q
            else:
                q = config(x + (change[:nv][joint_rates] if moved is None else moved))
            accelerations[i] = aba(model, data, q, here, table[4 * k + QUARTERS[i]])
        stages[k] = velocities
        step = (dt * WEIGHTS) @ slopes
        x += step[:nv][joint_rates]
        v = v + step[nv:]
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

"""The time series every export writes, taken from a plan's samples or resampled.

Without a rate, the series is the plan's own samples, unchanged. With a rate (Hz), the time
grid is ``0, 1/rate, 2/rate, ...`` plus the final instant ``T``, and every quantity is
recomputed consistently from the plan's polynomials and its robot (nothing is interpolated):

- joint positions, rates and accelerations: the plan's polynomials and their derivatives;
- base attitude: the base angular velocity ``F1(q) qdot`` (Pinocchio's centroidal map)
  integrated from the plan's start attitude by sixth-order Magnus steps of at most
  ``T / 2000``, as the planner does;
- base position and end-effector position: kinematics with the system CM at the origin
  (Pinocchio's centre of mass and frame placements);
- joint torques: inverse dynamics of the zero-momentum motion (Pinocchio's RNEA with the
  base acceleration solved from the centroidal map, as verification computes them; the
  plan's samples come from the centroidal map's time variation instead).

Both are computed :data:`_CHUNK` instants at a time, so a long export holds a few
megabytes of maps, not gigabytes.

At the plan's own sample instants the resampled values equal the plan's samples to the
planner's integration accuracy (tested).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..plans.format import Plan

__all__ = ["MAX_SAMPLES", "Trajectory", "check_rate", "from_samples", "resample", "trajectory"]

#: Largest number of instants a resampled export may hold.
MAX_SAMPLES = 2_000_000


@dataclass(frozen=True)
class Trajectory:
    """A plan as arrays over time.

    Attributes:
        joints: joint names, in order.
        kinds: per joint its URDF kind (``revolute``, ``continuous``, ``prismatic``).
        t: (K,) time (s).
        q: (K, N) joint positions (rad, or m for prismatic joints).
        qd: (K, N) joint rates (rad/s or m/s).
        qdd: (K, N) joint accelerations (rad/s^2 or m/s^2).
        tau: (K, N) joint torques (N m, or N for prismatic joints).
        base_quaternion_xyzw: (K, 4) base attitude in the inertial frame.
        base_position: (K, 3) base origin (m) in the inertial frame (origin: system CM).
        end_effector_position: (K, 3) end-effector position (m), same frame (the first one).
        resampled: whether the series was recomputed at a rate (else the plan's samples).
        end_effectors: every end-effector frame, in order (the first is the one above).
        end_effector_paths: (E, K, 3) each end effector's position (m), same frame.
    """

    joints: list[str]
    kinds: list[str]
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    base_quaternion_xyzw: np.ndarray
    base_position: np.ndarray
    end_effector_position: np.ndarray
    resampled: bool = False
    end_effectors: list[str] = field(default_factory=list)
    end_effector_paths: np.ndarray = field(default_factory=lambda: np.empty((0, 0, 3)))


def from_samples(plan: Plan) -> Trajectory:
    """The plan's own samples as arrays (torques must be present)."""
    s = plan.samples
    n = len(plan.robot.joints)
    tau = np.asarray(s.tau, dtype=float) if len(s.tau) else np.full((len(s.t), n), np.nan)
    return Trajectory(
        joints=list(plan.robot.joints),
        kinds=_kinds(plan),
        t=np.asarray(s.t, dtype=float),
        q=np.asarray(s.q, dtype=float),
        qd=np.asarray(s.qd, dtype=float),
        qdd=np.asarray(s.qdd, dtype=float),
        tau=tau,
        base_quaternion_xyzw=np.asarray(s.base_quaternion_xyzw, dtype=float),
        base_position=np.asarray(s.base_position, dtype=float),
        end_effector_position=np.asarray(s.end_effector_position, dtype=float),
        end_effectors=plan.robot.frames,
        end_effector_paths=np.asarray([s.path_of(f) for f in plan.robot.frames], dtype=float),
    )


def _kinds(plan: Plan) -> list[str]:
    kinds = list(plan.robot.joint_kinds)
    return kinds if len(kinds) == len(plan.robot.joints) else ["revolute"] * len(kinds or [])


def check_rate(rate: float, duration: float) -> int:
    """The number of instants ``rate`` (Hz) gives over ``duration`` (s), if an export may hold it.

    Raises:
        InputError: not a positive finite number, or more than :data:`MAX_SAMPLES` instants
            (with the largest rate that keeps them).
    """
    if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate > 0):
        raise InputError(f"--rate must be a positive number of Hz, got {rate}")
    span = duration * rate * (1 + 1e-12)  # beyond the floats for --rate 1e308
    count = math.floor(span) + 2 if span < MAX_SAMPLES else MAX_SAMPLES + 1
    if count > MAX_SAMPLES:
        # the largest rate that keeps the count, rounded down to 4 significant figures
        largest = (MAX_SAMPLES - 2) / (duration * (1 + 1e-12))
        scale = 10.0 ** (math.floor(math.log10(largest)) - 3)
        raise InputError(
            f"--rate {rate:g} Hz gives more than the {MAX_SAMPLES} samples an export may hold "
            f"over {duration:g} s (use a rate up to {math.floor(largest / scale) * scale:.4g} Hz)"
        )
    return count


def resample(plan: Plan, rate: float, times: np.ndarray | None = None) -> Trajectory:
    """Recompute the plan at ``rate`` (Hz) from its polynomials and robot (see module doc).

    Args:
        plan: the plan.
        rate: samples per second (Hz), positive.
        times: explicit instants (s) in [0, T], ascending, instead of the rate's grid (tests).

    Raises:
        InputError: ``rate`` is not a positive finite number or gives too many samples, or
            ``times`` are not ascending instants within the motion.
        ModelError: the plan's URDF cannot be loaded.
    """
    from ..physics.attitude import quat_rotate
    from ..physics.joint_torques import joint_torques_batch
    from ..physics.momentum import MomentumMap
    from ..plans.robot_copy import plan_robot

    T = plan.duration
    check_rate(rate, T)
    if times is None:
        grid = np.arange(0.0, T, 1.0 / rate)
        grid = grid[grid < T - 1e-9 * max(1.0, T)]
        times = np.append(grid, T)
    t = np.asarray(times, dtype=float)
    if t.ndim != 1 or not len(t) or np.any(np.diff(t) < 0.0) or t[0] < 0.0 or t[-1] > T:
        raise InputError(f"resampling instants must ascend within [0, {T:g}] s")
    robot = plan_robot(plan)
    mmap = MomentumMap(robot)
    frames = list(robot.end_effectors)
    path = plan.path()
    exact = path.evaluate(t)
    q, qd, qdd = exact.q, exact.qd, exact.qdd
    quats = _attitudes(plan, path, mmap, t)
    base, tau = np.empty((len(t), 3)), np.empty_like(q)
    ee = np.empty((len(frames), len(t), 3))
    for lo in range(0, len(t), _CHUNK):  # the centroidal maps of a chunk at once
        part = slice(lo, lo + _CHUNK)
        tau[part] = joint_torques_batch(mmap, q[part], qd[part], qdd[part])
        com, points = _centre_and_frames(mmap, q[part], frames)
        base[part] = quat_rotate(quats[part], -com)
        for e, point in enumerate(points):
            ee[e, part] = quat_rotate(quats[part], point - com)
    return Trajectory(
        joints=list(plan.robot.joints),
        kinds=_kinds(plan),
        t=t,
        q=q,
        qd=qd,
        qdd=qdd,
        tau=tau,
        base_quaternion_xyzw=quats,
        base_position=base,
        end_effector_position=ee[0],
        resampled=True,
        end_effectors=frames,
        end_effector_paths=ee,
    )


#: Magnus steps whose base rates are computed together (a bound on memory, not on accuracy).
_CHUNK = 4096


def _attitudes(plan: Plan, path: Any, mmap: Any, t: np.ndarray) -> np.ndarray:
    """(K, 4) base attitudes at the ascending instants ``t`` (s), from the plan's start.

    Sixth-order Magnus steps of at most ``T / 2000`` on a grid that contains every instant,
    taken :data:`_CHUNK` at a time (the base rates of millions of nodes at once would need
    gigabytes), each chunk from the last one's end.
    """
    from ..physics.attitude import magnus_increments, propagate, step_nodes

    T = plan.duration
    edges = [0.0]
    for a, b in zip(np.concatenate([[0.0], t[:-1]]), t, strict=True):
        if b > a:
            steps = max(1, math.ceil((b - a) / (T / 2000.0)))
            edges.extend(np.linspace(a, b, steps + 1)[1:].tolist())
    fine = np.asarray(edges)
    attitudes = np.empty((len(fine), 4))
    attitudes[0] = np.asarray(plan.base.start_quaternion_xyzw, float)
    for lo in range(0, len(fine) - 1, _CHUNK):
        piece = fine[lo : lo + _CHUNK + 1]
        nodes, h = step_nodes(piece)
        at_nodes = path.evaluate(nodes)
        omega = mmap.base_rates(at_nodes.q, at_nodes.qd).omega.reshape(-1, 3, 3)
        attitudes[lo : lo + len(piece)] = propagate(attitudes[lo], magnus_increments(omega, h))
    return attitudes[np.clip(np.searchsorted(fine, t), 0, len(fine) - 1)]


def _centre_and_frames(
    mmap: Any, joints: np.ndarray, frames: list[str]
) -> tuple[np.ndarray, list[np.ndarray]]:
    """(K, 3) system CM and (K, 3) per frame, base at the origin with identity attitude (m).

    By Pinocchio's own centre of mass and frame placements, one instant at a time (the
    plan's samples get theirs from the centroidal maps instead).
    """
    model, data = mmap.model, mmap.data
    ids = [model.getFrameId(f) for f in frames]
    configs = mmap.configurations(joints)
    com = np.empty((len(configs), 3))
    points = [np.empty((len(configs), 3)) for _ in frames]
    for k, config in enumerate(configs):
        com[k] = pin.centerOfMass(model, data, config)  # places the joints too
        for point, frame in zip(points, ids, strict=True):
            point[k] = pin.updateFramePlacement(model, data, frame).translation
    return com, points


def trajectory(plan: Plan, rate: float | None = None) -> Trajectory:
    """The plan's samples (``rate`` None) or the plan resampled at ``rate`` Hz."""
    return from_samples(plan) if rate is None else resample(plan, rate)

"""Joint torques alone of a zero-momentum motion at many instants (two Pinocchio calls each).

For checks that need only the torques (the dense effort-peak search, an effort value without
its gradient, the torques that drive the verification's forward-dynamics replay), at about a
third of the cost of :func:`~freefloat.physics.dynamics.inverse_dynamics_batch` (which also
gives the base wrench, CM and end effectors). In the base frame, base at the origin with
identity attitude (without gravity the torques do not depend on the base pose), with ``M``
the joint-space inertia and ``r(q, v, a)`` Pinocchio's RNEA:

- the centroidal map ``A_g = [A_b | A_j]`` gives the zero-momentum base twist
  ``v_b = -A_b^-1 A_j qdot``;
- the base rows of ``M`` are the whole system's momentum about the base origin, so they are
  ``A_g`` shifted from the CM ``c`` to the base origin: ``M_b = X A_g`` with
  ``X = [[I, 0], [[c]x, I]]``; ``c`` is read from ``A_g`` itself (its linear rows are
  ``m [I | -[c]x | ...]``);
- the base acceleration makes the base wrench zero: ``a_b = -M_bb^-1 r_b(q, v, [0; qddot])``,
  and the joint torques are ``tau = r_j(q, v, [0; qddot]) + M_jb a_b`` (``M_jb = M_bj^T``).

Units: joint values rad (or m), rates per unit time, torques N m (or N) for that time unit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .momentum import MomentumMap

__all__ = ["TorquesAndTwist", "joint_torques_and_twist", "joint_torques_batch"]


def joint_torques_batch(
    mmap: MomentumMap, joints: np.ndarray, rates: np.ndarray, accelerations: np.ndarray
) -> np.ndarray:
    """(K, N) joint torques (N m or N) of a zero-momentum motion at K instants.

    Args:
        mmap: momentum map of the robot (its Pinocchio model has no gravity).
        joints: (K, N) joint values (rad or m).
        rates: (K, N) joint rates (rad/s or m/s).
        accelerations: (K, N) joint accelerations (rad/s^2 or m/s^2).
    """
    return joint_torques_and_twist(mmap, joints, rates, accelerations).tau


@dataclass(frozen=True)
class TorquesAndTwist:
    """Joint torques of a zero-momentum motion and the base twist they come with.

    Attributes:
        tau: (K, N) joint torques (N m, or N for prismatic joints).
        twist: (K, 6) zero-momentum base twist ``[linear (m/s); angular (rad/s)]`` in the base
            frame, base at the origin.
    """

    tau: np.ndarray
    twist: np.ndarray


def joint_torques_and_twist(
    mmap: MomentumMap, joints: np.ndarray, rates: np.ndarray, accelerations: np.ndarray
) -> TorquesAndTwist:
    """:func:`joint_torques_batch` and the zero-momentum base twist it comes with.

    Arguments as :func:`joint_torques_batch`.
    """
    model, data = mmap.model, mmap.data
    joints = np.atleast_2d(np.asarray(joints, dtype=float))
    rates = np.atleast_2d(np.asarray(rates, dtype=float))
    accelerations = np.atleast_2d(np.asarray(accelerations, dtype=float))
    configs = mmap.configurations(joints)
    k_count, nv = len(configs), model.nv
    jv = np.array([j.idx_v for j in mmap.robot.joints], dtype=int)
    cmap, rnea = pin.computeCentroidalMap, pin.rnea
    ag = np.array([cmap(model, data, q) for q in configs]).reshape(k_count, 6, nv)
    v = np.zeros((k_count, nv))
    v[:, jv] = rates
    v[:, :6] = -np.linalg.solve(ag[:, :, :6], np.einsum("kij,kj->ki", ag, v)[..., None])[..., 0]
    a = np.zeros((k_count, nv))
    a[:, jv] = accelerations
    # base acceleration 0
    partial = np.array([rnea(model, data, *qva) for qva in zip(configs, v, a, strict=True)])
    partial = partial.reshape(k_count, nv)
    mmap.evaluations += k_count
    # M_b = X A_g: the angular rows gain c x (linear rows); c from A_g's linear rows
    cross = -ag[:, :3, 3:6] / ag[:, :1, :1]  # [c]x
    rows = ag.copy()
    rows[:, 3:] += cross @ ag[:, :3]
    a_base = -np.linalg.solve(rows[:, :, :6], partial[:, :6, None])[..., 0]
    tau = partial[:, jv] + np.einsum("kbj,kb->kj", rows[:, :, jv], a_base)
    return TorquesAndTwist(tau, v[:, :6].copy())

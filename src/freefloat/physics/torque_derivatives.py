"""Joint torques of a zero-momentum motion and their exact derivatives (Pinocchio RNEA).

Without gravity, the joint torques of a free floater with zero momentum depend only on the
joint values, rates and accelerations: the base twist and acceleration follow from them. In
the base frame (base at the origin, identity attitude; the torques do not depend on the base
pose), with ``M`` the joint-space inertia and ``r(q, v, a)`` Pinocchio's RNEA:

- the base twist ``v_b`` makes the momentum zero: ``M_bb v_b + M_bj qdot = 0`` (the base rows
  of ``M v`` are the whole system's momentum in the base frame);
- the base acceleration ``a_b`` makes the base wrench zero: ``r_b(q, v, a) = 0``;
- the joint torques are ``tau = r_j(q, v, a)``.

Differentiating the two base conditions (implicit functions ``v_b(q, qdot)`` and
``a_b(q, qdot, qddot)``) with Pinocchio's analytic RNEA derivatives gives ``dtau/dq``,
``dtau/dqdot`` and ``dtau/dqddot`` exactly. ``d(M v)/dq`` is the ``q`` derivative of
``r(q, 0, v)`` (no gravity, no velocity: ``r = M a``).

Units: joint values rad (or m), rates per unit time, torques N m (or N) for that time unit;
with normalised time ``s = t / T`` the torques are ``T^2`` times the torques in seconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .momentum import MomentumMap

__all__ = ["TorqueDerivatives", "torques_and_derivatives"]


@dataclass(frozen=True)
class TorqueDerivatives:
    """Joint torques at K instants and their derivatives.

    Attributes:
        tau: (K, N) joint torques (N m or N, in the time unit of the rates given).
        d_q: (K, N, N) ``dtau/dq`` (torque per rad or m).
        d_qd: (K, N, N) ``dtau/dqdot``.
        d_qdd: (K, N, N) ``dtau/dqddot`` (the reduced inertia, kg m^2 for revolute joints).
    """

    tau: np.ndarray
    d_q: np.ndarray
    d_qd: np.ndarray
    d_qdd: np.ndarray


def torques_and_derivatives(
    mmap: MomentumMap, joints: np.ndarray, rates: np.ndarray, accelerations: np.ndarray
) -> TorqueDerivatives:
    """Zero-momentum joint torques and their exact derivatives at K instants.

    Args:
        mmap: momentum map of the robot (its Pinocchio model has no gravity).
        joints: (K, N) joint values (rad or m).
        rates: (K, N) joint rates (rad or m per time unit).
        accelerations: (K, N) joint accelerations (per time unit squared).
    """
    model, data = mmap.model, mmap.data
    joints = np.atleast_2d(np.asarray(joints, dtype=float))
    rates = np.atleast_2d(np.asarray(rates, dtype=float))
    accelerations = np.atleast_2d(np.asarray(accelerations, dtype=float))
    configs = mmap.configurations(joints)
    k_count = len(joints)
    nv = model.nv
    jv = np.array([j.idx_v for j in mmap.robot.joints], dtype=int)
    # Pinocchio calls only in the loop; the linear algebra is batched over the instants.
    mass = np.empty((k_count, nv, nv))
    for k in range(k_count):
        mass[k] = pin.crba(model, data, configs[k])
    upper = np.triu(np.ones((nv, nv), dtype=bool))
    mass = np.where(upper, mass, np.swapaxes(mass, 1, 2))
    m_bb, m_bj = mass[:, :6, :6], mass[:, :6][:, :, jv]
    dvb_dqd = -np.linalg.solve(m_bb, m_bj)  # (K, 6, N): base twist per joint rate
    v = np.zeros((k_count, nv))
    v[:, jv] = rates
    v[:, :6] = np.einsum("kij,kj->ki", dvb_dqd, rates)
    a = np.zeros((k_count, nv))
    a[:, jv] = accelerations
    zero = np.zeros(nv)
    dmv_dq = np.empty((k_count, nv, nv))
    r_q = np.empty((k_count, nv, nv))
    r_v = np.empty((k_count, nv, nv))
    partial = np.empty((k_count, nv))
    for k in range(k_count):
        dmv_dq[k] = pin.computeRNEADerivatives(model, data, configs[k], zero, v[k])[0]
        partial[k] = pin.rnea(model, data, configs[k], v[k], a[k])  # base acceleration 0
    # base acceleration with zero base wrench: M_bb a_b + (r with a_b = 0)_b = 0
    a[:, :6] = -np.linalg.solve(m_bb, partial[:, :6, None])[..., 0]
    for k in range(k_count):
        derivatives = pin.computeRNEADerivatives(model, data, configs[k], v[k], a[k])
        r_q[k], r_v[k] = derivatives[0], derivatives[1]
    m_jb = mass[:, jv, :6]
    tau = partial[:, jv] + np.einsum("kij,kj->ki", m_jb, a[:, :6])
    # implicit derivatives of v_b (zero momentum) and a_b (zero base wrench)
    r_vbb = r_v[:, :6, :6]
    dvb_dq = -np.linalg.solve(m_bb, dmv_dq[:, :6][:, :, jv])
    dab_dq = -np.linalg.solve(m_bb, r_q[:, :6][:, :, jv] + r_vbb @ dvb_dq)
    dab_dqd = -np.linalg.solve(m_bb, r_v[:, :6][:, :, jv] + r_vbb @ dvb_dqd)
    dab_dqdd = dvb_dqd  # the same map: -M_bb^-1 M_bj
    r_vjb = r_v[:, jv, :6]
    d_q = r_q[:, jv][:, :, jv] + r_vjb @ dvb_dq + m_jb @ dab_dq
    d_qd = r_v[:, jv][:, :, jv] + r_vjb @ dvb_dqd + m_jb @ dab_dqd
    d_qdd = mass[:, jv][:, :, jv] + m_jb @ dab_dqdd
    mmap.evaluations += k_count
    return TorqueDerivatives(tau=tau, d_q=d_q, d_qd=d_qd, d_qdd=d_qdd)

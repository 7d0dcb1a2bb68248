"""Joint torques of a zero-momentum motion of the free-floating system.

Along a zero-momentum motion the centroidal momentum stays zero, so its rate does too:
``A_g a + dA_g v = 0``. Splitting ``a = [a_base; qddot]`` gives the base acceleration the joint
motion implies, and Pinocchio's inverse dynamics (RNEA) of the whole free-floating system with
that acceleration gives the joint torques of the reduced dynamics ``H qddot + C = tau`` (N m,
or N for prismatic joints). The six base entries of the RNEA result are the wrench the base
would need: zero up to rounding, a consistency check of its own. Gravity is zero. The
forward-dynamics replay driven by such torques is :mod:`freefloat.physics.replay`.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, fields

import numpy as np
import pinocchio as pin

from ..robot.model import Robot
from .momentum import MomentumMap

__all__ = [
    "InverseDynamics",
    "InverseDynamicsBatch",
    "centre_of_mass",
    "inverse_dynamics",
    "inverse_dynamics_batch",
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
    pose follow by one rotation and translation. Two Pinocchio calls per instant (the map and
    its rate in one, RNEA) and one per end effector (the CM comes with the centroidal maps:
    :func:`centre_of_mass`). The last batch per robot is kept: asked again for the very same
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
    """:func:`inverse_dynamics_batch`'s work: two Pinocchio calls per instant (and the frames).

    ``dA_g`` is linear in the velocity, and a base twist ``[v_b; w]`` (the base at the identity)
    moves the whole system rigidly: the momentum at the CM turns with ``w`` and does not shift
    with ``v_b``, so ``dA_g(q, [v_b; w; qdot]) = dA_g(q, [0; qdot]) + diag([w]x, [w]x) A_g``.
    Along a zero-momentum motion ``A_g v = 0``, hence ``dA_g(q, v) v = dA_g(q, [0; qdot]) v``:
    one ``computeCentroidalMapTimeVariation`` at the joint rates alone gives both ``A_g`` (for
    the twist) and the rate term, with no separate ``computeCentroidalMap``.
    """
    model, data = mmap.model, mmap.data
    configs = mmap.configurations(joints)
    k_count, nv = len(configs), model.nv
    dmap, place, rnea = pin.computeCentroidalMapTimeVariation, pin.updateFramePlacement, pin.rnea
    ag, d_ag = np.empty((k_count, 6, nv)), np.empty((k_count, 6, nv))
    frames = mmap.robot.end_effector_frames
    ee = np.empty((len(frames), k_count, 3))
    v = np.zeros((k_count, nv))
    v[:, 6:] = rates
    for q, velocity, slot, map_slot, *positions in zip(configs, v, d_ag, ag, *ee, strict=True):
        slot[...] = dmap(model, data, q, velocity)  # also places the joints
        map_slot[...] = data.Ag
        for position, frame in zip(positions, frames, strict=True):
            position[...] = place(model, data, frame).translation
    twist = -np.linalg.solve(ag[:, :, :6], np.einsum("kij,kj->ki", ag[:, :, 6:], rates)[..., None])
    twist = twist[..., 0]
    v[:, :6] = twist
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

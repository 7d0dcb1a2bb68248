"""The zero-momentum base rate and its joint-value derivative, batched over configurations.

:meth:`MomentumMap.base_rates <freefloat.physics.momentum.MomentumMap.base_rates>` asks
Pinocchio for the centroidal map (and its derivatives) one configuration at a time; here a
whole batch of K configurations goes through a few array operations per joint, with the batch
as the last (contiguous) axis of every array. The base is at the identity (base frame =
inertial frame), as there.

Spatial quantities are in the base frame about its origin: a motion ``[v; w]`` (v the velocity
of the point at the origin, m/s; w the angular velocity, rad/s), a momentum ``[p; L]`` (kg m/s;
kg m^2/s about the origin). A set of bodies of mass ``M`` (kg), first moment ``s`` (kg m) and
second moment ``E = sum m x x^T`` about the origin (kg m^2; rotational inertia
``J = tr(E) 1 - E``) has spatial inertia ``[[M, -[s]x], [[s]x, J]]``. Joint ``k`` has the axis
``S_k``: ``[o_k x a_k; a_k]`` for a turning joint through ``o_k`` along the unit axis ``a_k``,
``[a_k; 0]`` for a sliding one. With composite sums over the bodies distal to joint ``k``, the
momentum of its unit rate with the base still is ``[M_k v_k - s_k x w_k; s_k x v_k + J_k
w_k]``; about the centre of mass (CM) ``c`` its angular part is ``L - c x p``, column ``k`` of
``A_q[3:6]``, so ``F1 = -I_c^-1 A_q[3:6]`` (``I_c`` the locked inertia about ``c``).

Derivatives: moving joint ``j`` moves its distal bodies with spatial velocity ``S_j``, so at
fixed base twist and joint rates the total momentum about the origin changes by
``dh/dq_j = S_j x* h_j - I_j (S_j x V_j)``, with ``I_j`` the composite inertia, ``V_j`` the
velocity of the body the joint hangs from and ``h_j = I_j V_j + sum_{k distal} col_k qdot_k``
the momentum of the distal bodies. At the zero-momentum base twist the linear momentum is
zero, so the angular momentum about the CM changes by ``dL - c x dp`` (the CM's own motion
does not enter), and ``d omega / dq = -I_c^-1 (dL - c x dp)``: implicit differentiation of
``A_b v_base + A_q qdot = 0``, whose ``A_b^-1`` has angular rows ``[0, I_c^-1]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..robot.model import Robot

__all__ = ["BatchedCentroidal", "NodeRates"]


@dataclass(frozen=True)
class NodeRates:
    """Base angular velocity at K instants, and its sensitivities.

    Attributes:
        omega: (K, 3) base angular velocity, base frame (rad per unit time of ``rates``).
        f1: (K, 3, N) the map ``F1`` at each instant.
        domega_dq: (K, 3, N) derivative of ``omega`` with respect to the joint values at fixed
            joint rates (analytic); None unless asked.
    """

    omega: np.ndarray
    f1: np.ndarray
    domega_dq: np.ndarray | None = None


_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])
#: Below this determinant over the cube of the mean principal moment, inverses are LAPACK's.
CONDITION_FLOOR = 1e-6


class BatchedCentroidal:
    """Zero-momentum base angular velocity of one robot, K configurations per call.

    Built once per robot; holds no per-call state, so one instance may serve several threads.

    Args:
        robot: the robot (its Pinocchio model, free-flyer root, and 1-DoF joints).
    """

    def __init__(self, robot: Robot) -> None:
        model, n = robot.model, robot.n
        self._steps, self._vectors, weights = _tree(robot)
        self._weights = weights[:, :, None, None]  # per body: mass, principal second moments
        self._mass = weights[:, 0]  # (B,) kg
        # distal[k, b]: body b moves with robot joint k; the last row (all ones): whole system
        distal = np.ones((n + 1, len(weights)))
        for k, joint in enumerate(robot.joints):
            distal[k] = [joint.index in model.supports[b] for b in range(1, len(weights) + 1)]
        self._distal = distal
        self._composite_mass = distal @ self._mass  # (N + 1,) kg
        self._body = np.array([joint.index for joint in robot.joints], dtype=int)
        self._within = distal[:n, self._body - 1]  # [j, k]: joint k is distal to j (or is j)
        self._before = self._within.T - np.eye(n)  # [j, k]: joint k is proximal to joint j
        self._turning = np.array([joint.kind != "prismatic" for joint in robot.joints])

    def base_rates(
        self, joints: np.ndarray, rates: np.ndarray, derivatives: bool = False
    ) -> NodeRates:
        """Base angular velocity at K instants, as :meth:`MomentumMap.base_rates` gives it.

        Args:
            joints: (K, N) joint values (rad, or m for prismatic joints).
            rates: (K, N) joint rates (rad or m per unit of any time variable).
            derivatives: also return ``d omega / d q`` at fixed rates.

        Returns:
            ``omega`` (K, 3; rad per unit time, base frame), ``f1`` (K, 3, N) with
            ``omega = f1 @ rates``, and ``domega_dq`` (K, 3, N; per rad or m) if asked.
        """
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
        qdot = np.atleast_2d(np.asarray(rates, dtype=float)).T[:, None, None, :]  # (N,1,1,K)
        axes, first, inertia = self._composites(joints)
        n, mass = len(axes), self._composite_mass[:, None, None]
        centre = first[n] / mass[n]  # (3, K) m
        inverse = _inverse(inertia[n] - mass[n] * _rotational(_outer(centre, centre)))
        columns = _inertia_times(axes, mass[:n], first[:n], inertia[:n])
        f1 = -_apply(inverse, columns[:, 1] - _cross(centre, columns[:, 0]))  # (N, 3, K)
        omega = (f1 * qdot[:, 0]).sum(axis=0)
        domega = None
        if derivatives:
            # the base twist of zero momentum, the velocity of the body each joint hangs from
            momentum = (columns * qdot).reshape(n, -1)
            linear = _cross(first[n], omega) - momentum.sum(axis=0).reshape(2, 3, -1)[0]
            base = np.stack([linear / mass[n], omega])
            carrier = (self._before @ (axes * qdot).reshape(n, -1)).reshape(axes.shape)
            carrier += base
            distal = (self._within @ momentum).reshape(axes.shape)
            change = _momentum_change(axes, carrier, distal, mass[:n], first[:n], inertia[:n])
            domega = _apply(inverse, _cross(centre, change[:, 0]) - change[:, 1])
            domega = np.ascontiguousarray(domega.transpose(2, 1, 0))
        f1 = np.ascontiguousarray(f1.transpose(2, 1, 0))
        return NodeRates(omega=np.ascontiguousarray(omega.T), f1=f1, domega_dq=domega)

    def _composites(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Forward kinematics of a batch, and the mass distribution distal to each joint.

        Returns:
            (N, 2, 3, K) each robot joint's spatial axis ``[v, w]`` about the origin (m or 1
            per rad or m), then (N + 1, 3, K) the first moments (kg m) and (N + 1, 3, 3, K)
            the rotational inertias about the origin (kg m^2) of the bodies distal to each joint,
            the last entry the whole system's; all in the base frame.
        """
        count, n, bodies = len(joints), len(self._turning), len(self._mass)
        sine, versine = np.sin(joints.T), 1.0 - np.cos(joints.T)  # (N, K)
        origin = np.zeros((bodies + 1, 3, count))
        body = np.empty((bodies, 4, 3, count))  # per body: CoM, then principal axes (rotated)
        axes = np.zeros((n, 2, 3, count))
        # a body's rotation applied to its vectors, kept until its last child joint is placed
        turned = {
            0: np.broadcast_to(self._vectors[0][:, :, None], (*self._vectors[0].shape, count))
        }
        for j, (parent, k, turning, row, last) in enumerate(self._steps, start=1):
            out = turned.pop(parent) if last else turned[parent]
            terms = 9 if turning else 3
            origin[j] = origin[parent] + out[row + terms]
            if turning:  # columns of R_parent R_fixed (1 + sin K + (1 - cos) K^2)
                rotation = sine[k] * out[row + 3 : row + 6]
                rotation += out[row : row + 3]
                rotation += versine[k] * out[row + 6 : row + 9]
            else:
                rotation = np.ascontiguousarray(out[row : row + 3])
            if k >= 0:
                axes[k, int(turning)] = out[row + terms + 1]
                if not turning:  # a prismatic joint: along its axis, in its own (fixed) frame
                    origin[j] += out[row + terms + 1] * joints[:, k]
            product = (self._vectors[j] @ rotation.reshape(3, -1)).reshape(-1, 3, count)
            body[j - 1] = product[:4]
            if len(product) > 4:
                turned[j] = product
        body[:, 0] += origin[1:]
        lin = _cross(origin[self._body], axes[:, 1])
        axes[:, 0] += np.where(self._turning[:, None, None], lin, 0.0)
        first = self._distal @ (self._mass[:, None, None] * body[:, 0]).reshape(bodies, -1)
        moments = np.einsum("bmik,bmlk->bilk", self._weights * body, body)
        second = self._distal @ moments.reshape(bodies, -1)
        inertia = _rotational(second.reshape(n + 1, 3, 3, count))
        return axes, first.reshape(n + 1, 3, count), inertia


def _tree(
    robot: Robot,
) -> tuple[list[tuple[int, int, bool, int, bool]], list[np.ndarray], np.ndarray]:
    """The kinematic tree as :meth:`BatchedCentroidal._composites` walks it.

    Body ``j`` is the one joint ``j`` carries (0: the universe). Each body lists the vectors
    its rotation turns into the base frame: its CoM offset (m) and principal axes, then for
    each child joint the columns of the fixed rotation (for a turning joint three stacks, the
    terms ``R, R K, R K^2`` of Rodrigues' formula), the fixed offset (m) and the axis.

    Returns:
        per joint after the universe: parent, column of its value (-1: not the robot's, kept at
        its neutral placement), whether it turns, its first row in the parent's vectors, and
        whether it is the parent's last child; per body its (rows, 3) vectors; and (B, 4) the
        mass (kg) and principal second moments about the CoM (kg m^2) of each body.
    """
    model = robot.model
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    column = {joint.index: k for k, joint in enumerate(robot.joints)}
    vectors: list[list[np.ndarray]] = [[] for _ in range(model.njoints)]
    steps, weights = [], []
    for j in range(1, model.njoints):
        k, parent = column.get(j, -1), int(model.parents[j])
        fixed = model.jointPlacements[j] if k >= 0 else data.liMi[j]
        motion = np.asarray(data.joints[j].S, dtype=float).ravel()
        turning = k >= 0 and bool(np.any(motion[3:6]))
        axis = motion[3:6] if turning else motion[0:3]
        axis = axis / (np.linalg.norm(axis) or 1.0)
        skew = _skew(axis)
        terms = (np.eye(3), skew, skew @ skew) if turning else (np.eye(3),)
        last = j == max(i for i in range(1, model.njoints) if model.parents[i] == parent)
        steps.append((parent, k, turning, len(vectors[parent]), last))
        vectors[parent] += [c for t in terms for c in (fixed.rotation @ t).T]
        vectors[parent] += [fixed.translation, fixed.rotation @ axis]
        inertia = model.inertias[j]
        second = 0.5 * np.trace(inertia.inertia) * np.eye(3) - inertia.inertia
        values, principal = np.linalg.eigh(second)  # E = sum_m e_m u_m u_m^T
        vectors[j] += [np.asarray(inertia.lever, dtype=float), *principal.T]
        weights.append([inertia.mass, *values])
    return steps, [np.array(v, dtype=float).reshape(-1, 3) for v in vectors], np.array(weights)


def _inertia_times(
    motion: np.ndarray, mass: np.ndarray, first: np.ndarray, inertia: np.ndarray
) -> np.ndarray:
    """Spatial inertias times motions: ``[M v - s x w; s x v + J w]``, (..., N, 2, 3, K).

    Args:
        motion: (..., N, 2, 3, K) motions ``[v, w]`` (m/s, rad/s).
        mass: (N, 1, 1) per joint the distal bodies' mass (kg).
        first: (N, 3, K) their first moment (kg m).
        inertia: (N, 3, 3, K) their rotational inertia about the origin (kg m^2).
    """
    cross = _cross(first[:, None], motion)  # [s x v, s x w]
    out = np.empty(np.broadcast_shapes(motion.shape, cross.shape))
    out[..., 0, :, :] = mass * motion[..., 0, :, :] - cross[..., 1, :, :]
    out[..., 1, :, :] = cross[..., 0, :, :] + _apply(inertia, motion[..., 1, :, :])
    return out


def _momentum_change(
    axes: np.ndarray,
    carrier: np.ndarray,
    distal: np.ndarray,
    mass: np.ndarray,
    first: np.ndarray,
    inertia: np.ndarray,
) -> np.ndarray:
    """``dh/dq_j = S_j x* h_j - I_j (S_j x V_j)`` at fixed rates, ``[dp, dL]`` (N, 2, 3, K).

    Args:
        axes: (N, 2, 3, K) each joint's spatial axis ``S_j = [v, w]``.
        carrier: (N, 2, 3, K) the velocity ``V_j`` of the body each joint hangs from.
        distal: (N, 2, 3, K) ``sum_{k distal to j} col_k qdot_k``, the momentum of the distal
            joints' motion (kg m/s, kg m^2/s per unit time).
        mass: (N, 1, 1) the distal bodies' mass (kg).
        first: (N, 3, K) their first moment (kg m).
        inertia: (N, 3, 3, K) their rotational inertia about the origin (kg m^2).
    """
    lin, ang = axes[:, 0], axes[:, 1]
    turn = _cross(ang[:, None], carrier)  # [w x v_c, w x w_c]
    turn[:, 0] += _cross(lin, carrier[:, 1])  # now S_j x V_j
    momentum = _inertia_times(carrier, mass, first, inertia) + distal  # h_j
    change = _cross(ang[:, None], momentum)
    change[:, 1] += _cross(lin, momentum[:, 0])
    return change - _inertia_times(turn, mass, first, inertia)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the second-last axis (length 3), broadcasting the others."""
    out = a.take(_NEXT, -2) * b.take(_AFTER, -2)
    out -= a.take(_AFTER, -2) * b.take(_NEXT, -2)
    return out


def _outer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3, K) outer products ``a b^T`` of (3, K) vectors."""
    return a[:, None, :] * b[None, :, :]


def _rotational(second: np.ndarray) -> np.ndarray:
    """In place, the rotational inertias ``tr(E) 1 - E`` (kg m^2) of (..., 3, 3, K) ``E``."""
    trace = second[..., 0, 0, :] + second[..., 1, 1, :] + second[..., 2, 2, :]
    np.negative(second, out=second)
    for i in range(3):
        second[..., i, i, :] += trace
    return second


def _apply(matrices: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """``matrices @ vectors`` per batch entry: (..., 3, 3, K) times (..., 3, K)."""
    return np.einsum("...ijk,...jk->...ik", matrices, vectors)


def _inverse(matrix: np.ndarray) -> np.ndarray:
    """(3, 3, K) inverses of (3, 3, K) symmetric positive definite matrices (kg m^2 -> 1/...).

    By cofactors: the rows of the inverse are ``c1 x c2, c2 x c0, c0 x c1`` over the
    determinant (``c`` the columns), accurate for a well-conditioned matrix such as a locked
    inertia (a 20 m x 1 m x 1 m box: principal moments 1 : 200 : 200). A batch with a
    determinant below :data:`CONDITION_FLOOR` times the cube of its mean principal moment
    (moments spread over about three orders of magnitude or more, where the cofactors lose
    digits) is inverted by LAPACK instead.
    """
    columns = matrix.transpose(1, 0, 2)  # [c]: column c
    rows = _cross(columns.take(_NEXT, 0), columns.take(_AFTER, 0))
    determinant = (rows[0] * columns[0]).sum(axis=0)
    scale = (matrix[0, 0] + matrix[1, 1] + matrix[2, 2]) / 3.0
    if not np.all(determinant > CONDITION_FLOOR * scale**3):
        return np.ascontiguousarray(np.linalg.inv(matrix.transpose(2, 0, 1)).transpose(1, 2, 0))
    return rows / determinant


def _skew(axis: np.ndarray) -> np.ndarray:
    """The cross-product matrix of ``axis``: ``_skew(a) @ v == a x v``."""
    return np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])

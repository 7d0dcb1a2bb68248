"""Base attitude: quaternions, ZYX Euler angles, geodesic error and propagation.

Quaternions are unit 4-vectors in Pinocchio's order ``[x, y, z, w]``. The base angular velocity
``omega`` (rad/s) is expressed in the base frame, so the attitude obeys
``d/dt quat = 1/2 quat (x) (omega, 0)`` (docs/method.md section 3). ZYX Euler angles are
``(yaw, pitch, roll)`` in rad: yaw about z, then pitch about the new y, then roll about the new x.

Propagation uses a sixth-order Magnus integrator on three Gauss-Legendre nodes per step
(Blanes, Casas and Ros). Along a rotation about a fixed axis (the planar case) it reduces
exactly to three-point Gauss-Legendre quadrature of the yaw rate, a plain integral.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = [
    "GAUSS3_NODES",
    "GAUSS3_WEIGHTS",
    "IDENTITY",
    "geodesic_angle",
    "magnus_increment_jacobian",
    "magnus_increments",
    "ordered_product",
    "propagate",
    "quat_conjugate",
    "quat_exp",
    "quat_from_zyx",
    "quat_log",
    "quat_multiply",
    "quat_rate_matrices",
    "quat_to_matrix",
    "relative_quat",
    "relative_rotvec",
    "rotation_matrices",
    "so3_right_jacobian",
    "step_nodes",
    "zyx_from_quat",
    "zyx_from_quats",
]

#: Identity quaternion ``[x, y, z, w]``.
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])

#: Three-point Gauss-Legendre nodes and weights on [0, 1].
GAUSS3_NODES = np.array([0.5 - math.sqrt(15.0) / 10.0, 0.5, 0.5 + math.sqrt(15.0) / 10.0])
GAUSS3_WEIGHTS = np.array([5.0, 8.0, 5.0]) / 18.0


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of 3-vectors along the last axis (broadcasts; cheaper than ``np.cross``)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a (x) b`` of ``[x, y, z, w]`` quaternions (broadcasts over rows)."""
    av, aw = a[..., :3], a[..., 3:]
    bv, bw = b[..., :3], b[..., 3:]
    vec = aw * bv + bw * av + cross3(av, bv)
    w = aw * bw - np.sum(av * bv, axis=-1, keepdims=True)
    return np.concatenate([vec, w], axis=-1)


def quat_conjugate(q: np.ndarray) -> np.ndarray:
    """Conjugate (inverse of a unit quaternion) ``[-x, -y, -z, w]``."""
    return np.concatenate([-q[..., :3], q[..., 3:]], axis=-1)


def quat_exp(rotvec: np.ndarray) -> np.ndarray:
    """Unit quaternion of a rotation vector (rad; broadcasts over rows)."""
    rotvec = np.asarray(rotvec, dtype=float)
    angle = np.linalg.norm(rotvec, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(x/2)/x, with its series near 0 to keep full precision.
    small = angle < 1e-4
    safe = np.where(small, 1.0, angle)
    factor = np.where(small, 0.5 - angle**2 / 48.0, np.sin(half) / safe)
    return np.concatenate([factor * rotvec, np.cos(half)], axis=-1)


def quat_log(q: np.ndarray) -> np.ndarray:
    """Rotation vector (rad, angle in [0, pi]) of a unit quaternion."""
    q = np.asarray(q, dtype=float)
    q = np.where(q[..., 3:] < 0.0, -q, q)
    vec, w = q[..., :3], q[..., 3:]
    norm = np.linalg.norm(vec, axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(norm, w)
    small = norm < 1e-12
    factor = np.where(small, 2.0 / np.where(w == 0.0, 1.0, w), angle / np.where(small, 1.0, norm))
    return factor * vec


def relative_quat(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation taking attitude ``a`` to attitude ``b``, in ``a``'s frame: ``conj(a) (x) b``.

    Unit quaternions ``[x, y, z, w]``; broadcasts like :func:`quat_multiply`.
    """
    return quat_multiply(quat_conjugate(a), b)


def relative_rotvec(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation vector (rad, in ``a``'s frame, angle in [0, pi]) taking attitude ``a`` to ``b``.

    :func:`quat_log` of :func:`relative_quat`.
    """
    return quat_log(relative_quat(a, b))


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (base frame to inertial frame) of a unit quaternion ``[x, y, z, w]``.

    Broadcasts: (..., 4) quaternions give (..., 3, 3) matrices.
    """
    q = np.asarray(q, dtype=float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty((*q.shape[:-1], 3, 3))
    out[..., 0, 0], out[..., 0, 1] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w)
    out[..., 0, 2], out[..., 1, 0] = 2 * (x * z + y * w), 2 * (x * y + z * w)
    out[..., 1, 1], out[..., 1, 2] = 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
    out[..., 2, 0], out[..., 2, 1] = 2 * (x * z - y * w), 2 * (y * z + x * w)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Vectors ``v`` (base frame) rotated into the inertial frame by unit quaternions ``q``.

    Broadcasts over rows: ``q`` (..., 4) ``[x, y, z, w]`` and ``v`` (..., 3), same unit out.
    """
    u, w = q[..., :3], q[..., 3:]
    uv = cross3(u, v)
    return v + 2.0 * w * uv + 2.0 * cross3(u, uv)


def quat_from_zyx(yaw: float, pitch: float = 0.0, roll: float = 0.0) -> np.ndarray:
    """Unit quaternion of ZYX Euler angles (rad): ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    return np.array(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ]
    )


#: Below this value of ``cos(pitch / 2) -+ sin(pitch / 2)`` the attitude counts as gimbal-locked
#: and roll is reported as 0: the rotation then moves by at most ``2 pi`` times this (rad).
_LOCKED = 1e-13


def zyx_from_quat(q: Sequence[float] | np.ndarray) -> np.ndarray:
    """ZYX Euler angles ``[yaw, pitch, roll]`` (rad) of a unit quaternion, accurate everywhere.

    Yaw and roll lie in (-pi, pi], pitch in [-pi/2, pi/2]. At pitch = +-pi/2 the split between
    yaw and roll is not unique (gimbal lock): roll is then reported as 0.

    With half angles ``a = yaw/2``, ``b = pitch/2``, ``c = roll/2`` the quaternion's pairs are
    ``w + y = P cos(a - c)``, ``z - x = P sin(a - c)``, ``w - y = M cos(a + c)``, ``z + x =
    M sin(a + c)``, with ``P = cos b + sin b`` and ``M = cos b - sin b`` (both >= 0). So
    ``pitch = 2 atan2(P - M, P + M)`` is exact to rounding at every attitude (an ``asin`` loses
    half the digits near the lock), and the half-angle sum and difference each come from their
    own pair: near pitch = +-pi/2 the ill-determined one is scaled by M (or P) in the
    rotation, so the angles returned give back the attitude to about 1e-15 rad.
    """
    return np.array(_zyx(*(float(c) for c in q)))


def zyx_from_quats(quats: np.ndarray) -> np.ndarray:
    """(K, 3) :func:`zyx_from_quat` of K unit quaternions (rad), the same formulas in numpy.

    Equal to the single quaternion's to rounding (numpy's ``hypot`` and ``arctan2`` may
    differ from :mod:`math`'s in the last bit). Where that bit could decide a discrete choice,
    yaw or roll within :data:`_SEAM` of +-pi (which side of the wrap) or a pair within
    :data:`_SEAM` of the gimbal-lock threshold, the row is the single quaternion's own. The
    wrap into (-pi, pi] is exact, as ``math.remainder``'s: the half-angle sum and difference
    lie in [-pi, pi], so yaw and roll lie in [-2 pi, 2 pi] and one subtraction or addition of
    2 pi, exact there, wraps them.
    """
    quats = np.asarray(quats, dtype=float).reshape(-1, 4)
    x, y, z, w = quats.T
    plus, minus = np.hypot(w + y, z - x), np.hypot(w - y, z + x)
    pitch = 2.0 * np.arctan2(plus - minus, plus + minus)
    difference = np.arctan2(z - x, w + y)  # a - c
    total = np.arctan2(z + x, w - y)  # a + c
    locked_up, locked_down = minus < _LOCKED, (minus >= _LOCKED) & (plus < _LOCKED)
    total = np.where(locked_up, difference, total)  # pitch = +pi/2: only a - c matters
    difference = np.where(locked_down, total, difference)  # pitch = -pi/2: only a + c
    out = np.stack([_wrapped(total + difference), pitch, _wrapped(total - difference)], axis=1)
    seam = np.abs(out[:, [0, 2]]).max(axis=1) > math.pi - _SEAM
    seam |= np.abs(np.minimum(plus, minus) - _LOCKED) < _SEAM
    for k in np.flatnonzero(seam).tolist():
        out[k] = _zyx(*quats[k].tolist())
    return out


#: Yaw or roll this close to +-pi (rad), or a pair this close to the gimbal-lock threshold:
#: the batched Euler angles take the single quaternion's own row there.
_SEAM = 1e-9


def _wrapped(angles: np.ndarray) -> np.ndarray:
    """Angles in [-2 pi, 2 pi] (rad) wrapped into (-pi, pi], as :func:`_wrap` wraps each."""
    out = np.where(angles > math.pi, angles - 2.0 * math.pi, angles)
    out = np.where(out < -math.pi, out + 2.0 * math.pi, out)
    return np.where(out == -math.pi, math.pi, out)


def _zyx(x: float, y: float, z: float, w: float) -> tuple[float, float, float]:
    """:func:`zyx_from_quat` on plain floats."""
    plus, minus = math.hypot(w + y, z - x), math.hypot(w - y, z + x)
    pitch = 2.0 * math.atan2(plus - minus, plus + minus)
    difference = math.atan2(z - x, w + y)  # a - c
    total = math.atan2(z + x, w - y)  # a + c
    if minus < _LOCKED:  # pitch = +pi/2: only a - c matters; roll 0
        total = difference
    elif plus < _LOCKED:  # pitch = -pi/2: only a + c matters; roll 0
        difference = total
    yaw, roll = total + difference, total - difference
    return _wrap(yaw), pitch, _wrap(roll)


def _wrap(angle: float) -> float:
    """``angle`` (rad) wrapped into (-pi, pi]."""
    wrapped = math.remainder(angle, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


def geodesic_angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle (rad, in [0, pi]) of the rotation taking attitude ``a`` to attitude ``b``.

    ``conj(a) (x) b`` on plain floats (cheaper than numpy for two 4-vectors), the products in
    :func:`quat_multiply`'s order.
    """
    ax, ay, az, aw = _floats(a)
    bx, by, bz, bw = _floats(b)
    x = aw * bx - bw * ax - (ay * bz - az * by)
    y = aw * by - bw * ay - (az * bx - ax * bz)
    z = aw * bz - bw * az - (ax * by - ay * bx)
    w = aw * bw + (ax * bx + ay * by + az * bz)
    return 2.0 * math.atan2(math.hypot(x, y, z), abs(w))


def _floats(q: Sequence[float] | np.ndarray) -> list[float]:
    """The entries of a quaternion as Python floats."""
    if isinstance(q, list):
        return [float(c) for c in q]
    return np.asarray(q, dtype=float).tolist()


def step_nodes(edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gauss nodes of each integration step.

    Args:
        edges: ascending step boundaries (any unit of time), M + 1 values.

    Returns:
        ``(nodes, h)``: the 3M node times, step by step, and the M step lengths.
    """
    h = np.diff(edges)
    nodes = (edges[:-1, None] + h[:, None] * GAUSS3_NODES[None, :]).ravel()
    return nodes, h


def so3_right_jacobian(phi: np.ndarray) -> np.ndarray:
    """Right Jacobians of SO(3), (M, 3, 3).

    To first order, ``exp(phi + d) = exp(phi) exp(Jr(phi) d)`` (rotation vectors in rad).
    """
    phi = np.atleast_2d(phi)
    theta = np.linalg.norm(phi, axis=1)
    small = theta < 1e-5
    t = np.where(small, 1.0, theta)
    a = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(t)) / t**2)
    b = np.where(small, 1.0 / 6.0 - theta**2 / 120.0, (t - np.sin(t)) / t**3)
    skew = np.zeros((len(phi), 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -phi[:, 2], phi[:, 1], -phi[:, 0]
    skew[:, 1, 0], skew[:, 2, 0], skew[:, 2, 1] = phi[:, 2], -phi[:, 1], phi[:, 0]
    return np.eye(3) - a[:, None, None] * skew + b[:, None, None] * (skew @ skew)


def rotation_matrices(rotvec: np.ndarray) -> np.ndarray:
    """(M, 3, 3) rotation matrices of rotation vectors (rad)."""
    return quat_to_matrix(quat_exp(np.atleast_2d(rotvec)))


def magnus_increment_jacobian(omega: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Exact derivative of each step's Magnus vector with respect to its node rates.

    Returns (M, 3, 9): ``dW_m / d omega_m[node, axis]`` with columns ordered node-major. The
    Magnus vector is a polynomial of the node rates, so complex-step differentiation is exact
    to rounding.
    """
    eps = 1e-30
    steps = len(h)
    shifted = np.repeat(omega.astype(complex)[None], 9, axis=0)  # (9, M, 3, 3): one per column
    for column in range(9):
        shifted[column, :, column // 3, column % 3] += 1j * eps
    moved = magnus_increments(shifted.reshape(9 * steps, 3, 3), np.tile(h, 9)).imag / eps
    return moved.reshape(9, steps, 3).transpose(1, 2, 0)


def magnus_increments(omega: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Sixth-order Magnus rotation vector of each step (rad).

    Args:
        omega: angular velocity at the step nodes, shape (M, 3 nodes, 3), base frame, rad per
            unit of the step variable.
        h: the M step lengths.

    Returns:
        (M, 3) rotation vectors ``W`` with ``quat_end = quat_start (x) exp(W)``.
    """
    a = omega * h[:, None, None]
    a1, a2, a3 = a[:, 0], a[:, 1], a[:, 2]
    alpha1 = a2
    alpha2 = math.sqrt(15.0) / 3.0 * (a3 - a1)
    alpha3 = 10.0 / 3.0 * (a3 - 2.0 * a2 + a1)

    def bracket(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        # Lie bracket of the generators for a body-frame rate (quat' = quat (x) omega / 2).
        return cross3(v, u)

    c1 = bracket(alpha1, alpha2)
    c2 = -bracket(alpha1, 2.0 * alpha3 + c1) / 60.0
    return alpha1 + alpha3 / 12.0 + bracket(-20.0 * alpha1 - alpha3 + c1, alpha2 + c2) / 240.0


def propagate(quat0: np.ndarray, increments: np.ndarray) -> np.ndarray:
    """Chain step rotations: returns the M + 1 attitudes ``[x, y, z, w]`` from ``quat0``."""
    steps = quat_exp(increments).tolist()
    out = [list(map(float, quat0))]
    x, y, z, w = out[0]
    for bx, by, bz, bw in steps:  # Hamilton products on plain floats: cheap for 4-vectors
        x, y, z, w = (
            w * bx + bw * x + y * bz - z * by,
            w * by + bw * y + z * bx - x * bz,
            w * bz + bw * z + x * by - y * bx,
            w * bw - x * bx - y * by - z * bz,
        )
        out.append([x, y, z, w])
    result = np.array(out)
    result /= np.linalg.norm(result, axis=1, keepdims=True)
    return result


def quat_rate_matrices(omega: np.ndarray) -> np.ndarray:
    """(..., 4, 4) matrices ``A`` with ``A y = 0.5 y (x) [omega, 0]`` for ``[x, y, z, w]`` y.

    ``omega``: (..., 3) base angular velocities (rad/s, base frame); ``A`` is in 1/s.
    """
    omega = np.asarray(omega, dtype=float)
    a = np.zeros((*omega.shape[:-1], 4, 4))
    x, y, z = omega[..., 0], omega[..., 1], omega[..., 2]
    # vector part: w omega - omega x v ; scalar part: -omega . v
    a[..., 0, 1], a[..., 0, 2], a[..., 0, 3] = z, -y, x
    a[..., 1, 0], a[..., 1, 2], a[..., 1, 3] = -z, x, y
    a[..., 2, 0], a[..., 2, 1], a[..., 2, 3] = y, -x, z
    a[..., 3, 0], a[..., 3, 1], a[..., 3, 2] = -x, -y, -z
    return 0.5 * a


def ordered_product(factors: np.ndarray) -> np.ndarray:
    """``F[K-1] ... F[1] F[0]`` of (K, 4, 4) matrices (K >= 1), by pairwise reduction."""
    phi = np.asarray(factors, dtype=float)
    eye = np.eye(phi.shape[-1])
    while len(phi) > 1:
        if len(phi) % 2:
            phi = np.concatenate([phi, eye[None]])
        phi = phi[1::2] @ phi[0::2]
    return phi[0]

"""The planar momentum map as cosine polynomials, for fast vectorised evaluation.

For a planar chain of revolute joints turning about the axis ``n`` (docs/method.md sections 3 and
7), the base rate is ``omega_n = -(n . A_q qdot) / (n . A_w n)``, where ``A_w`` and ``A_q`` are
the angular-momentum rows of Pinocchio's centroidal map for the base rotation and the joint
rates. Each of these entries is a trigonometric polynomial of the joint angles: a constant plus
cosines and sines of the sums of contiguous joint angles ``q_a + ... + q_b`` (the relative
angle between bodies a-1 and b). Method.md section 7 shows the two-joint case
(``D0 + D1 + D2`` and ``D1 + D2``, ``D2``).

:func:`identify` finds those coefficients from Pinocchio by least squares on random
configurations and accepts them only if they reproduce Pinocchio on fresh configurations to
1e-12 (relative); then the gains ``g_i = d yaw / d q_i`` and their derivatives are evaluated for
many configurations at once in a few array operations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..robot.content_cache import RobotCache
from ..robot.model import Robot
from .momentum import cached_planar_axis

__all__ = ["PlanarMap", "cached_identify", "identify"]

#: Relative accuracy the identified polynomials must reach against Pinocchio.
IDENTIFICATION_TOLERANCE = 1e-12


def _spans(n: int) -> list[tuple[int, int]]:
    return [(a, b) for a in range(n) for b in range(a, n)]


def _membership(n: int) -> np.ndarray:
    """(spans, N) membership of each joint in each contiguous span of joints."""
    spans = _spans(n)
    member = np.zeros((len(spans), n))
    for k, (a, b) in enumerate(spans):
        member[k, a : b + 1] = 1.0
    return member


def _features(q: np.ndarray, member: np.ndarray) -> np.ndarray:
    """Features (..., F): 1, then the cosines and the sines of every span's angle sum."""
    sums = q @ member.T
    return np.concatenate([np.ones((*q.shape[:-1], 1)), np.cos(sums), np.sin(sums)], axis=-1)


@dataclass(frozen=True)
class PlanarMap:
    """Cosine-polynomial form of a planar robot's gains ``g(q)`` (rad of yaw per rad).

    Attributes:
        axis: the planar axis (unit vector, base frame).
        den: coefficients of ``n . A_w n`` (kg m^2) on the features.
        num: (features, N) coefficients of ``n . A_q`` (kg m^2) on the features.
        error: largest relative mismatch against Pinocchio found when checking.
    """

    axis: np.ndarray
    den: np.ndarray
    num: np.ndarray
    error: float

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.num.shape[1])

    def _parts(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Membership matrix and the constant, cosine and sine coefficients of [den | num]."""
        parts = self.__dict__.get("_parts_cache")
        if parts is None:
            member = _membership(self.n)
            spans = member.shape[0]
            both = np.concatenate([self.den[:, None], self.num], axis=1)  # (F, 1 + N)
            parts = (member, both[0], both[1 : 1 + spans], both[1 + spans :])
            object.__setattr__(self, "_parts_cache", parts)
        return parts

    def gains(self, q: np.ndarray) -> np.ndarray:
        """Gains ``g(q)`` (..., N) for joint values ``q`` (..., N) in rad."""
        member, const, cos_c, sin_c = self._parts()
        sums = np.asarray(q, dtype=float) @ member.T
        both = const + np.cos(sums) @ cos_c + np.sin(sums) @ sin_c  # (..., 1 + N)
        return -both[..., 1:] / both[..., :1]

    def gains_and_derivatives(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Gains (..., N) and their derivatives ``dg_i/dq_j`` (..., N, N)."""
        member, const, cos_c, sin_c = self._parts()
        sums = np.asarray(q, dtype=float) @ member.T
        cos, sin = np.cos(sums), np.sin(sums)
        both = const + cos @ cos_c + sin @ sin_c  # (..., 1 + N): [den | num]
        den, num = both[..., 0], both[..., 1:]
        # d/dq_j of a span's cos is -sin when joint j is in the span (and cos for its sin).
        weights = -sin[..., :, None] * cos_c + cos[..., :, None] * sin_c  # (..., S, 1 + N)
        dboth = np.swapaxes(weights, -1, -2) @ member  # (..., 1 + N, N): [i, j]
        dden, dnum = dboth[..., 0, :], dboth[..., 1:, :]
        gains = -num / den[..., None]
        dgains = -dnum / den[..., None, None] + num[..., :, None] * dden[..., None, :] / (
            den[..., None, None] ** 2
        )
        return gains, dgains


def _angular_rows(robot: Robot, data: pin.Data, q: np.ndarray, axis: np.ndarray) -> np.ndarray:
    config = robot.configuration(q)
    ag = pin.computeCentroidalMap(robot.model, data, config)
    rows = axis @ ag[3:6]
    return np.concatenate([[rows[3:6] @ axis], rows[6:]])


def identify(robot: Robot, axis: np.ndarray, seed: int = 0) -> PlanarMap | None:
    """Identify the cosine polynomials of a planar all-revolute robot; None if not exact.

    Args:
        robot: the robot (planar about ``axis``).
        axis: its planar axis (unit vector, base frame).
        seed: seed of the random configurations.
    """
    if any(not joint.angular for joint in robot.joints):
        return None
    n = robot.n
    data = robot.model.createData()
    rng = np.random.default_rng(seed)
    member = _membership(n)
    features = 1 + 2 * len(member)
    fit_q = rng.uniform(-np.pi, np.pi, (4 * features, n))
    check_q = rng.uniform(-np.pi, np.pi, (64, n))
    values = np.array([_angular_rows(robot, data, q, axis) for q in fit_q])
    coeffs = np.linalg.lstsq(_features(fit_q, member), values, rcond=None)[0]
    truth = np.array([_angular_rows(robot, data, q, axis) for q in check_q])
    predicted = _features(check_q, member) @ coeffs
    error = float(np.abs(predicted - truth).max() / np.abs(truth).max())
    if not error <= IDENTIFICATION_TOLERANCE:
        return None
    return PlanarMap(axis, coeffs[:, 0], coeffs[:, 1:], error)


#: Identified planar maps (None: not identifiable), computed once per robot content.
_MAPS: RobotCache[PlanarMap | None] = RobotCache()


def cached_identify(robot: Robot) -> PlanarMap | None:
    """:func:`identify` about the robot's own planar axis, computed once per robot content.

    None when the robot is not planar, or its map is not identifiable. The axis is derived
    from the robot (:func:`~.momentum.cached_planar_axis`), so everything the map depends on is
    in the content key.
    """

    def compute() -> PlanarMap | None:
        axis = cached_planar_axis(robot)
        return None if axis is None else identify(robot, axis)

    return _MAPS.get(robot, compute)

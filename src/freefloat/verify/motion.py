"""How fast any point of a robot's bodies can move along a polynomial path: exact bounds.

Verification's clearance certificate (:mod:`freefloat.verify.certificate`) needs, for each
interval of time, an upper bound of the speed of every point of every checked body relative to
the spacecraft (bodies fixed to the spacecraft do not move in its frame). It is

    |v_p|  <=  sum over the joints j that move the body of  c[j, body] * max |qd_j| on the interval

with ``c`` the body's reach from joint ``j``'s axis for a revolute joint (m per rad: the link
offsets down the chain plus the body's bounding sphere, whatever the configuration) and 1 for a
prismatic one (its rate is a speed). The joint-rate maxima are exact: ``|qd_j|`` is largest at
an end of the interval or at a real root of ``qdd_j`` inside it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..robot.model import Robot

__all__ = ["PolynomialMotion", "reach_coefficients"]


class PolynomialMotion:
    """Joint paths as polynomials in time (ascending powers, s), with exact rate extremes.

    Args:
        coefficients: per joint, ascending coefficients of q(t) (rad or m; t in s).
        duration: the path's duration (s).
    """

    def __init__(self, coefficients: Sequence[Sequence[float]], duration: float) -> None:
        poly = np.polynomial.polynomial
        self.duration = float(duration)
        self.q = [np.asarray(c, dtype=float) for c in coefficients]
        self.qd = [poly.polyder(c) for c in self.q]
        roots: list[tuple[float, int]] = []
        for j, c in enumerate(self.q):
            acceleration = poly.polyder(c, 2)
            if len(acceleration) < 2 or not np.any(acceleration[1:]):
                continue
            for r in np.atleast_1d(poly.polyroots(np.trim_zeros(acceleration, "b"))):
                if abs(r.imag) <= 1e-9 * max(1.0, abs(r.real)) and 0.0 < r.real < self.duration:
                    roots.append((float(r.real), j))
        roots.sort()
        self._root_times = np.array([r for r, _ in roots])
        self._root_joints = np.array([j for _, j in roots], dtype=int)
        self._q_matrix = _padded(self.q)
        self._qd_matrix = _padded(self.qd)
        self._root_rates = np.array(
            [abs(poly.polyval(t, self.qd[j])) for t, j in roots], dtype=float
        )

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.q)

    def joints(self, t: float) -> np.ndarray:
        """Joint values (rad or m) at time ``t`` (s)."""
        return _horner(self._q_matrix, np.array([t], dtype=float))[0]

    def rates(self, t: np.ndarray) -> np.ndarray:
        """(K, N) joint rates (rad/s or m/s) at the times ``t`` (s)."""
        return _horner(self._qd_matrix, np.atleast_1d(np.asarray(t, dtype=float)))

    def rate_bounds(self, t0: np.ndarray, t1: np.ndarray) -> np.ndarray:
        """(K, N) largest ``|qd_j|`` over each ``[t0, t1]`` (rad/s or m/s), exact up to rounding.

        A root found slightly off (rounding) can only move an interior extremum by a tiny
        amount, so the bounds are padded by a relative 1e-9.
        """
        t0, t1 = np.atleast_1d(np.asarray(t0, float)), np.atleast_1d(np.asarray(t1, float))
        ends = np.abs(self.rates(np.concatenate([t0, t1])))
        bound = np.maximum(ends[: len(t0)], ends[len(t0) :])
        lo = np.searchsorted(self._root_times, t0)
        hi = np.searchsorted(self._root_times, t1)
        for i in np.flatnonzero(hi > lo):
            for k in range(lo[i], hi[i]):
                j = self._root_joints[k]
                bound[i, j] = max(bound[i, j], self._root_rates[k])
        return bound * (1.0 + 1e-9) + 1e-15


def _padded(coefficients: list[np.ndarray]) -> np.ndarray:
    """(N, D) ascending coefficients, zero-padded to one degree."""
    width = max(1, max(len(c) for c in coefficients))
    out = np.zeros((len(coefficients), width))
    for j, c in enumerate(coefficients):
        out[j, : len(c)] = c
    return out


def _horner(matrix: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(K, N) values of N polynomials (rows of ``matrix``, ascending) at K times ``t``."""
    out = np.zeros((len(t), matrix.shape[0]))
    for column in matrix.T[::-1]:
        out = out * t[:, None] + column
    return out


def reach_coefficients(
    robot: Robot, geometry: pin.GeometryModel, centres: np.ndarray, radii: np.ndarray
) -> np.ndarray:
    """(N, G): how fast geometry ``g`` can move per unit rate of joint ``j`` (m/s per rad/s).

    Revolute joint: the farthest any point of the geometry can be from the joint's origin (on
    its axis), whatever the joints between: the sum of the joint offsets down the chain, the
    travel of prismatic joints on it, and the geometry's offset plus bounding radius.
    Prismatic joint: 1. Joints that do not move the geometry: 0.

    Args:
        robot: the robot.
        geometry: its geometry model (object placements in their joint's frame).
        centres: (G, 3) bounding-sphere centres in each geometry's own frame (m).
        radii: (G,) bounding-sphere radii (m).
    """
    model = robot.model
    column = {j.index: k for k, j in enumerate(robot.joints)}
    prismatic = {j.index for j in robot.joints if j.kind == "prismatic"}
    travel = {
        j.index: max(abs(j.lower), abs(j.upper)) if np.isfinite(j.lower + j.upper) else 0.0
        for j in robot.joints
    }
    out = np.zeros((robot.n, len(geometry.geometryObjects)))
    for g, obj in enumerate(geometry.geometryObjects):
        reach = float(np.linalg.norm(obj.placement.act(centres[g]))) + float(radii[g])
        joint = int(obj.parentJoint)
        while joint > 1:  # up the chain to the free flyer
            if joint in column:
                out[column[joint], g] = 1.0 if joint in prismatic else reach
            reach += float(np.linalg.norm(model.jointPlacements[joint].translation))
            if joint in prismatic:
                reach += travel[joint]
            joint = int(model.parents[joint])
    return out

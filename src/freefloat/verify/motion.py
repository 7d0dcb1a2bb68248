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

from collections.abc import Callable, Sequence

import numpy as np
import pinocchio as pin

from ..robot.model import Robot

__all__ = ["PathFunction", "PolynomialMotion", "joint_axes", "reach_coefficients"]

#: ``path(t)``: joint values, rates and accelerations, each (K, N), at K times t (s).
PathFunction = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


class PolynomialMotion:
    """Polynomial joint paths on [0, T] with exact extremes of the joint rates.

    Args:
        path: ``path(t)`` gives the joint values, rates and accelerations, each (K, N), at the
            times ``t`` (s); for example a plan file's own definition
            (:func:`~freefloat.verify.path_eval.file_path`).
        duration: T (s).
        degree: the paths' polynomial degree (at least that of every joint).
        positions: ``positions(t)`` gives the joint values alone, (K, N), the same as
            ``path(t)[0]`` at less cost (one instant at a time, as halving asks); optional.
    """

    def __init__(
        self,
        path: PathFunction,
        duration: float,
        degree: int,
        positions: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> None:
        self.path = path
        self._positions = positions
        self.duration = float(duration)
        # Each joint's acceleration is a polynomial of degree <= degree - 2: interpolated at
        # that many Chebyshev points it is exact up to rounding, and its real roots in (0, T)
        # are where the rates peak.
        # (chebfit and chebroots: what Chebyshev.fit on [-1, 1] and its roots() compute)
        points = max(degree - 1, 1)
        chebyshev = np.polynomial.chebyshev
        x = np.cos(np.pi * (np.arange(points) + 0.5) / points)
        acceleration = path(0.5 * (x + 1.0) * self.duration)[2]
        roots: list[tuple[float, int]] = []
        #: Each joint's acceleration as a Chebyshev series on [-1, 1] (None: constant).
        self._series: list[np.ndarray | None] = []
        for j in range(acceleration.shape[1]):
            coef = chebyshev.chebfit(x, acceleration[:, j], points - 1)
            constant = not np.any(np.abs(coef[1:]) > 0.0)
            self._series.append(None if constant else coef)
            if not constant:
                roots += _inside(chebyshev.chebroots(coef), self.duration, j)
        self._root_times, self._root_joints, self._root_rates = _at_roots(path, roots, 1)
        self._peaks: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    @classmethod
    def from_monomials(
        cls, coefficients: Sequence[Sequence[float]], duration: float
    ) -> PolynomialMotion:
        """Paths given by ascending monomial coefficients in t (s) per joint."""
        poly = np.polynomial.polynomial
        q = [np.asarray(c, dtype=float) for c in coefficients]

        def path(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            t = np.atleast_1d(np.asarray(t, dtype=float))
            return tuple(  # type: ignore[return-value]
                np.stack([poly.polyval(t, poly.polyder(c, k)) for c in q], axis=-1)
                for k in range(3)
            )

        return cls(path, duration, max(len(c) for c in q) - 1)

    def joints(self, t: float) -> np.ndarray:
        """Joint values (rad or m) at time ``t`` (s)."""
        if self._positions is not None:
            return self._positions(np.array([t], dtype=float))[0]
        return self.path(np.array([t], dtype=float))[0][0]

    def rates(self, t: np.ndarray) -> np.ndarray:
        """(K, N) joint rates (rad/s or m/s) at the times ``t`` (s)."""
        return self.path(np.atleast_1d(np.asarray(t, dtype=float)))[1]

    def rate_bounds(
        self, t0: np.ndarray, t1: np.ndarray, ends: np.ndarray | None = None
    ) -> np.ndarray:
        """(K, N) largest ``|qd_j|`` over each ``[t0, t1]`` (rad/s or m/s), exact up to rounding.

        A root found slightly off (rounding) can only move an interior extremum by a tiny
        amount, so the bounds are padded by a relative 1e-9. ``ends``: the (2 K, N) ``|qd|``
        at the ``t0`` then at the ``t1``, if already evaluated.
        """
        t0, t1 = np.atleast_1d(np.asarray(t0, float)), np.atleast_1d(np.asarray(t1, float))
        if ends is None:
            ends = np.abs(self.rates(np.concatenate([t0, t1])))
        found = (self._root_times, self._root_joints, self._root_rates)
        return _interval_maxima(t0, t1, ends, found)

    def acceleration_bounds(self, t0: np.ndarray, t1: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """(K, N) largest ``|qdd_j|`` over each ``[t0, t1]`` (rad/s^2 or m/s^2).

        As :meth:`rate_bounds`; ``ends``: the (2 K, N) ``|qdd|`` at the ``t0`` then at the
        ``t1``. The interior extremes lie at the real roots of the jerk (the acceleration's
        derivative).
        """
        t0, t1 = np.atleast_1d(np.asarray(t0, float)), np.atleast_1d(np.asarray(t1, float))
        if self._peaks is None:  # the jerk's real roots, found when first asked for
            chebyshev = np.polynomial.chebyshev
            peaks = [
                root
                for j, coef in enumerate(self._series)
                if coef is not None and len(coef) > 2 and np.any(np.abs(coef[2:]) > 0.0)
                for root in _inside(chebyshev.chebroots(chebyshev.chebder(coef)), self.duration, j)
            ]
            self._peaks = _at_roots(self.path, peaks, 2)
        return _interval_maxima(t0, t1, ends, self._peaks)


def _inside(roots: np.ndarray, duration: float, joint: int) -> list[tuple[float, int]]:
    """The real ``roots`` in (-1, 1) as times in (0, ``duration``) (s), each with ``joint``."""
    return [
        (0.5 * (float(r.real) + 1.0) * duration, joint)
        for r in np.atleast_1d(roots)
        if abs(r.imag) <= 1e-9 and -1.0 < r.real < 1.0
    ]


def _at_roots(
    path: PathFunction, roots: list[tuple[float, int]], order: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sorted root times (s), their joints, and ``|derivative order|`` of each joint there."""
    roots = sorted(roots)
    times = np.array([r for r, _ in roots])
    joints = np.array([j for _, j in roots], dtype=int)
    if not roots:
        return times, joints, np.zeros(0)
    values = path(times)[order]
    return times, joints, np.abs(values[np.arange(len(roots)), joints])


def _interval_maxima(
    t0: np.ndarray,
    t1: np.ndarray,
    ends: np.ndarray,
    found: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> np.ndarray:
    """(K, N) the larger of the ``ends`` (2 K, N) and the interior extremes ``found`` in each.

    ``found``: the sorted times (s), joints and absolute values of the interior extremes.
    Padded by a relative 1e-9 (a root found slightly off moves its extremum by a tiny amount).
    """
    times, joints, values = found
    bound = np.maximum(ends[: len(t0)], ends[len(t0) :])
    lo = np.searchsorted(times, t0)
    hi = np.searchsorted(times, t1)
    for i in np.flatnonzero(hi > lo):
        for k in range(lo[i], hi[i]):
            j = joints[k]
            bound[i, j] = max(bound[i, j], values[k])
    return bound * (1.0 + 1e-9) + 1e-15


def reach_coefficients(
    robot: Robot,
    geometry: pin.GeometryModel,
    centres: np.ndarray,
    radii: np.ndarray,
    owners: np.ndarray | None = None,
) -> np.ndarray:
    """(N, G): how fast geometry ``g`` can move per unit rate of joint ``j`` (m/s per rad/s).

    Revolute joint: the farthest any point of the geometry can be from the joint's axis,
    whatever the joints between. For the geometry's own joint, the distance of its
    bounding-sphere centre from the axis plus the radius (fixed in that joint's frame). For a
    joint further up the chain, the distance from its axis of the next joint's origin down the
    chain (fixed in its frame), plus the farthest the geometry can be from that origin: the
    sum of the joint offsets further down, the travel of prismatic joints on it, and the
    geometry's offset plus bounding radius. Prismatic joint: 1. Joints that do not move the
    geometry: 0.

    Args:
        robot: the robot.
        geometry: its geometry model (object placements in their joint's frame).
        centres: (S, 3) bounding-sphere centres in their geometry's own frame (m).
        radii: (S,) bounding-sphere radii (m).
        owners: (S,) the geometry each sphere bounds (part of); default one per geometry.

    Returns:
        (N, S) for each sphere (G columns by default).
    """
    model = robot.model
    column = {j.index: k for k, j in enumerate(robot.joints)}
    prismatic = {j.index for j in robot.joints if j.kind == "prismatic"}
    travel = {
        j.index: max(abs(j.lower), abs(j.upper)) if np.isfinite(j.lower + j.upper) else 0.0
        for j in robot.joints
    }
    axes = joint_axes(robot)
    objects = list(geometry.geometryObjects)
    owners = np.arange(len(objects)) if owners is None else np.asarray(owners, dtype=int)
    rotations = np.array([obj.placement.rotation for obj in objects]).reshape(-1, 3, 3)
    offsets = np.array([obj.placement.translation for obj in objects]).reshape(-1, 3)
    local = np.einsum("sij,sj->si", rotations[owners], centres) + offsets[owners]
    radii = np.asarray(radii, dtype=float)
    # the farthest from the geometry's own joint's origin: its offset plus bounding radius
    own = np.linalg.norm(local, axis=1) + radii
    parents = np.array([int(obj.parentJoint) for obj in objects], dtype=int)[owners]
    out = np.zeros((robot.n, len(owners)))
    for start in np.unique(parents).tolist():
        spheres = parents == start
        if start in column and start not in prismatic:  # its own joint: from the axis
            out[column[start], spheres] = _off_axis(local[spheres], axes[start]) + radii[spheres]
        elif start in column:
            out[column[start], spheres] = 1.0
        added, joint = 0.0, start  # added: the offsets from ``joint``'s origin down the chain
        while joint > 1:  # up the chain to the free flyer
            parent = int(model.parents[joint])
            step = model.jointPlacements[joint].translation  # joint's origin in parent's frame
            if parent in column and parent not in prismatic:
                lever = float(_off_axis(step[None], axes[parent])[0])
                out[column[parent], spheres] = (
                    lever + own[spheres] + added + (travel[joint] if joint in prismatic else 0.0)
                )
            elif parent in column:
                out[column[parent], spheres] = 1.0
            added += float(np.linalg.norm(step)) + (travel[joint] if joint in prismatic else 0.0)
            joint = parent
    return out


def joint_axes(robot: Robot) -> dict[int, np.ndarray]:
    """Each joint's unit axis in its own frame, by Pinocchio joint index.

    The angular (revolute) or linear (prismatic) part of the joint's motion subspace, read from
    its local Jacobian column at the neutral configuration (the same at any configuration for
    one-degree-of-freedom joints).
    """
    model = robot.model
    data, q = model.createData(), pin.neutral(model)
    out = {}
    for joint in robot.joints:
        column = pin.computeJointJacobian(model, data, q, joint.index)[:, joint.idx_v]
        axis = column[:3] if joint.kind == "prismatic" else column[3:]
        out[joint.index] = axis / np.linalg.norm(axis)
    return out


def _off_axis(points: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """(S,) distances (m) of points (S, 3) from the line through the origin along unit ``axis``."""
    along = points @ axis
    return np.sqrt(np.maximum(np.einsum("si,si->s", points, points) - along * along, 0.0))

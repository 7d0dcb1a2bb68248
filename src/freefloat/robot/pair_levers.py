"""Lever arms of the bounding spheres about the joint axes: pairs' speed bounds on an interval.

:func:`~freefloat.robot.motion_bound.motion_weights` bounds how fast a pair's distance can
change whatever the configuration: per joint, the reach of a body's bounding sphere from the
joint's origin, the arm stretched out. At an instant, the distance from a revolute joint's
axis to the sphere's centre is known exactly from the kinematics, and a folded arm's spheres
lie far nearer the axes than their reach. That distance changes no faster than the centre
moves relative to the joint's frame, which only the joints further down the chain move: at
most ``D_j = sum_i m_i c_i`` over those joints i (``m_i`` a bound of joint i's rate on the
interval, rad/s; ``c_i`` the centre's reach from it, m). On ``[t0, t1]`` every point of the
sphere then lies within

    lever_j  =  min(reach_j, (arm_j(t0) + arm_j(t1) + (t1 - t0) D_j) / 2)

of joint j's axis (m; ``arm`` the centre's distance from the axis plus the radius: the two
lines rising from the ends at slope ``D_j`` meet at most that high). A pair's distance changes
no faster than its two bodies' points move relative to each other: the joints that move one
body alone, each at most ``m_j lever_j`` (m/s); those that move both move them as one. The
speed is never above that of the motion weights (``m @ weights``), which caps it.

Revolute joints only: with a prismatic joint the collision model has no motion weights and no
lever arms (:class:`~freefloat.robot.pair_queries.PairQueries`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from .model import Robot
from .motion_bound import alone, sphere_reach
from .sphere_kinematics import SphereKinematics

__all__ = ["PairLevers"]


class PairLevers:
    """Lever arms of the collision model's bounding spheres, and its pairs' speed bounds.

    Args:
        robot: the robot (revolute joints only).
        geometry: the collision geometry model (G objects).
        pairs: the checked pairs, as indices into the objects.
        centres: (G, 3) each object's bounding-sphere centre in its own frame (m).
        radii: (G,) their radii (m).
        kinematics: places the spheres and the joint axes (built with the same centres).
        weights: (P, N) the pairs' :func:`~freefloat.robot.motion_bound.motion_weights`
            (m per rad), as the collision model holds them.
    """

    def __init__(
        self,
        robot: Robot,
        geometry: pin.GeometryModel,
        pairs: Sequence[tuple[int, int]],
        centres: np.ndarray,
        radii: np.ndarray,
        kinematics: SphereKinematics,
        weights: np.ndarray,
    ) -> None:
        found = sphere_reach(robot, geometry, centres, radii)
        if found is None:
            raise ValueError("lever arms need revolute joints only (a prismatic joint has none)")
        reach, carried = found
        self.kinematics = kinematics
        #: (P, N) the motion weights (m per rad): the cap of every speed.
        self.weights = weights
        #: (G, N) each sphere's reach from each joint (m per rad; 0 where it does not move it).
        self.reach = reach
        self.radii = np.asarray(radii, dtype=float)
        #: (G, N) how fast each sphere's centre moves per unit rate of each joint (m per rad).
        self.centre_reach = np.where(carried, np.maximum(reach - self.radii[:, None], 0.0), 0.0)
        #: (G * N, P) sums a pair's speed from its objects' per-joint speeds: 1.0 at
        #: (object, joint) where the joint moves that object of the pair and not the other.
        self.gather = np.zeros((*reach.shape, len(pairs)))
        pair_array = np.array(pairs, dtype=int).reshape(-1, 2)
        for side, moved in enumerate(alone(carried, pairs)):
            self.gather[pair_array[:, side], :, np.arange(len(pairs))] += moved
        self.gather = self.gather.reshape(reach.size, len(pairs))
        #: (N, N) ``below[i, j]``: joint i lies further down the chain than joint j.
        self.below = _below(robot)

    def arms(self, joints: np.ndarray) -> np.ndarray:
        """(B, G, N) each sphere's lever arm about each joint's axis at (B, N) joints (rad, m).

        The distance from the axis to the sphere's centre plus its radius, exact at those
        joints (for a joint that does not move the sphere it means nothing: its reach, 0, caps
        it in :meth:`speeds`).
        """
        centres, origins, axes = self.kinematics.placed(joints)
        # per coordinate: (B, G, N) offsets of the centres from the origins, (B, 1, N) axes
        x, y, z = centres.transpose(2, 0, 1)[..., None] - origins.transpose(2, 0, 1)[:, :, None]
        a, b, c = axes.transpose(2, 0, 1)[:, :, None]
        square = (y * c - z * b) ** 2 + (z * a - x * c) ** 2 + (x * b - y * a) ** 2
        return np.sqrt(square) + self.radii[:, None]  # |offset x axis|: no cancellation

    def levers(
        self, rates: np.ndarray, widths: np.ndarray, ends: tuple[np.ndarray, np.ndarray]
    ) -> np.ndarray:
        """(I, G, N) how far every point of each sphere stays from each joint's axis (m).

        On each of I intervals: ``min(reach, (arm(t0) + arm(t1) + (t1 - t0) D) / 2)`` (the
        module doc; 0 where the joint does not move the sphere).

        Args:
            rates: (I, N) bounds of the joint rates on the intervals (rad/s).
            widths: (I,) the intervals' widths (s).
            ends: (I, G, N) the spheres' :meth:`arms` at the intervals' starts, and at their
                ends (m).
        """
        drift = (rates[:, None, :] * self.centre_reach) @ self.below  # (I, G, N), m/s
        rising = 0.5 * (ends[0] + ends[1] + widths[:, None, None] * drift)
        return np.minimum(self.reach, rising)

    def speeds(
        self, rates: np.ndarray, widths: np.ndarray, ends: tuple[np.ndarray, np.ndarray]
    ) -> np.ndarray:
        """(I, P) bounds of how fast each pair's distance can change on I intervals (m/s).

        Per pair, the sum over the joints that move one of its objects alone of the joint's
        rate bound times that object's :meth:`levers`; never above the motion weights' bound
        ``rates @ weights.T``. Arguments as for :meth:`levers`.
        """
        moved = self.levers(rates, widths, ends) * rates[:, None, :]  # (I, G, N), m/s
        speed = moved.reshape(len(rates), -1) @ self.gather
        return np.minimum(speed, rates @ self.weights.T)


def _below(robot: Robot) -> np.ndarray:
    """(N, N) ``below[i, j]``: 1.0 where the robot's joint i lies further down than joint j."""
    column = {joint.index: k for k, joint in enumerate(robot.joints)}
    parents = [int(p) for p in robot.model.parents]
    below = np.zeros((robot.n, robot.n))
    for joint, i in column.items():
        up = parents[joint]
        while up > 0:
            if up in column:
                below[i, column[up]] = 1.0
            up = parents[up]
    return below

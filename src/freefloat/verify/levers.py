"""Lever arms of the checked spheres about each joint's axis: tighter speed bounds on an interval.

:func:`~freefloat.verify.motion.reach_coefficients` bounds, whatever the configuration, how far
any point of a sphere (a body's bounding sphere or one of its leaf spheres) can lie from each
joint's axis, by the joint offsets down the chain: the arm stretched out. At an instant the
distance from a revolute joint's axis to the sphere's centre is known exactly, from the
joint's frame and the centre's position; a folded arm's spheres lie far nearer the axes than
their reach. That distance changes no faster than the centre moves relative to the joint's
frame, at most ``D_j = sum over the joints i further down the chain of m_i c_i`` (``m_i`` the
rate bound of joint i on the interval, ``c_i`` the centre's reach from it: the sphere's reach
less its radius, or 1 for a prismatic joint), so on ``[a, b]`` every point of the sphere lies
within

    lever_j  =  min(reach_j, (arm_j(a) + arm_j(b) + (b - a) D_j) / 2)

of joint j's axis (``arm`` the centre's distance from the axis plus the radius; the two lines
rising from the ends at slope ``D_j`` meet at most that high). A point's speed is then at most
``sum_j m_j lever_j``, in place of ``sum_j m_j reach_j``. Prismatic joints keep their reach, 1.
Everything here is the verification's own: the URDF's kinematics through Pinocchio's joint
frames, the meshes' own spheres.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..robot.model import Robot
from .motion import joint_axes

__all__ = ["Levers"]


class Levers:
    """Lever arms of S spheres about the robot's N joint axes (see the module doc).

    Args:
        robot: the robot.
        reach: (N, S) each sphere's reach from each joint
            (:func:`~freefloat.verify.motion.reach_coefficients`; m per rad, 1 for prismatic).
        radii: (S,) the spheres' radii (m).
    """

    def __init__(
        self, robot: Robot, geometry: pin.GeometryModel, reach: np.ndarray, radii: np.ndarray
    ) -> None:
        axes = joint_axes(robot)
        self.joints = [j.index for j in robot.joints]
        #: (N, 3) each joint's axis in its own frame, and which joints turn.
        self.axes = np.array([axes[j] for j in self.joints]).reshape(-1, 3)
        #: Per joint an object on its link, and the joint's origin and axis in that object's
        #: frame (the joints' placements from the objects'); None if a joint's link has none.
        self.carriers = _carriers(self.joints, self.axes, geometry)
        self.revolute = np.array([j.kind != "prismatic" for j in robot.joints], dtype=bool)
        self.radii = np.asarray(radii, dtype=float)
        #: (S, N) the reaches, one sphere a row; the radii, or inf where a joint does not turn
        #: the sphere (its lever is then its reach: 1 or 0).
        self.reach_t = np.ascontiguousarray(reach.T)
        turning = self.revolute[:, None] & (reach > 0.0)
        self.pad = np.ascontiguousarray((np.where(turning, 0.0, np.inf) + self.radii).T)
        #: (S, N) how fast each sphere's centre moves per unit rate of each joint.
        centre = np.where(self.revolute[:, None], reach - self.radii, reach)
        self.centre_t = np.ascontiguousarray(np.where(reach > 0.0, np.maximum(centre, 0.0), 0.0).T)
        #: (N, N) below[j, i]: joint i lies further down the chain than joint j.
        below = np.zeros((len(self.joints), len(self.joints)))
        column = {j: k for k, j in enumerate(self.joints)}
        parents = [int(p) for p in robot.model.parents]
        for i, joint in enumerate(self.joints):
            up = parents[joint]
            while up > 0:
                if up in column:
                    below[column[up], i] = 1.0
                up = parents[up]
        #: (N, N) its transpose, for rows of rates times reaches.
        self.below_t = np.ascontiguousarray(below.T)

    def axes_from(self, placements: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The joints' origins (..., N, 3) (m) and unit axes (..., N, 3) from object poses.

        ``placements``: (..., G, 4, 4) every object's pose (spacecraft frame). None when a
        joint's link carries no object (:meth:`axes_at` then, from the joints' frames).
        """
        if self.carriers is None:
            return None
        objects, origins, axes = self.carriers
        poses = placements[..., objects, :, :]
        rotations = poses[..., :3, :3]
        world = np.einsum("...nij,nj->...ni", rotations, origins) + poses[..., :3, 3]
        return world, np.einsum("...nij,nj->...ni", rotations, axes)

    def axes_at(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The joints' origins (..., N, 3) (m) and unit axes (..., N, 3), spacecraft frame.

        ``frames``: (..., N, 4, 4) the joints' frames
        (:meth:`~freefloat.verify.clearance.MeshClearance.pose`).
        """
        return frames[..., :3, 3], np.einsum("...nij,nj->...ni", frames[..., :3, :3], self.axes)

    def arms(
        self, origins: np.ndarray, axes: np.ndarray, centres: np.ndarray, spheres: np.ndarray
    ) -> np.ndarray:
        """(..., N) the lever arms of spheres about each joint at their instants (m).

        A revolute joint that moves the sphere: its centre's distance from the axis plus its
        radius. Other joints: inf (:meth:`lever` then takes their reach, 1 or 0).

        Args:
            origins: (..., N, 3) the joints' origins at each sphere's instant (:meth:`axes_at`).
            axes: (..., N, 3) their unit axes.
            centres: (..., 3) the spheres' centres (m, spacecraft frame).
            spheres: (...) which of the S spheres they are.
        """
        offset = centres[..., None, :] - origins  # (..., N, 3)
        along = np.einsum("...ni,...ni->...n", offset, axes)
        square = np.einsum("...ni,...ni->...n", offset, offset) - along * along
        return np.sqrt(np.maximum(square, 0.0)) + self.pad[spheres]

    def lever(
        self,
        widths: np.ndarray,
        rates: np.ndarray,
        ends: tuple[np.ndarray, np.ndarray],
        centre: np.ndarray,
        reach: np.ndarray,
    ) -> np.ndarray:
        """(H, s, N) the lever arms of spheres that hold over H intervals (m; the module doc).

        Args:
            widths: (H,) the intervals' widths (s).
            rates: (H, N) the joint-rate bounds on them (rad/s or m/s).
            ends: (H, s, N) the spheres' arms at the intervals' starts, and at their ends
                (:meth:`arms`; inf where the reach stands).
            centre: the spheres' rows of :attr:`centre_t`, (s, N) or per interval (H, s, N).
            reach: their rows of :attr:`reach_t`, the same shape.
        """
        drift = (rates[:, None, :] * centre) @ self.below_t
        rising = 0.5 * (ends[0] + ends[1] + widths[:, None, None] * drift)
        return np.minimum(reach, rising)


def _carriers(
    joints: list[int], axes: np.ndarray, geometry: pin.GeometryModel
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Per joint the first object on its link, and the joint's origin (m) and axis there."""
    objects: list[int] = []
    for joint in joints:
        on = [g for g, obj in enumerate(geometry.geometryObjects) if obj.parentJoint == joint]
        if not on:
            return None
        objects.append(on[0])
    placements = [geometry.geometryObjects[g].placement for g in objects]
    rotations = np.array([p.rotation for p in placements]).reshape(-1, 3, 3)
    offsets = np.array([p.translation for p in placements]).reshape(-1, 3)
    # the object's frame from the joint's: x_joint = R x_object + p, so x_object = R^T (x - p)
    origins = -np.einsum("nji,nj->ni", rotations, offsets)
    return np.array(objects, dtype=int), origins, np.einsum("nji,nj->ni", rotations, axes)

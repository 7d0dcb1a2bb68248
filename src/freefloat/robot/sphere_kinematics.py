"""Where the collision shapes' bounding spheres are, at many joint vectors in one call.

The collision model bounds every pair's distance by its shapes' bounding spheres before it asks
coal for exact distances (:mod:`freefloat.robot.collision`). Pinocchio places the shapes one
configuration at a time, and reading each placement back into Python costs more than the
exact query it spares; here the sphere centres of a whole batch of configurations come from one
forward pass of array operations over the kinematic tree: per joint, its parent's placement,
its fixed placement in the parent, and its own motion (a rotation about, or a translation
along, its axis by the joint value). The spacecraft is at the identity, as in the collision
model; joints that are not the robot's (the free flyer) keep their neutral placement.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .model import Robot

__all__ = ["SphereKinematics"]


class SphereKinematics:
    """Bounding-sphere centres of a geometry model's shapes, batched over joint vectors.

    Args:
        robot: the robot (its Pinocchio model and 1-DoF joints).
        geometry: the collision geometry model.
        centres: (G, 3) each shape's bounding-sphere centre in the shape's own frame (m).
    """

    def __init__(self, robot: Robot, geometry: pin.GeometryModel, centres: np.ndarray) -> None:
        model = robot.model
        data = model.createData()
        pin.forwardKinematics(model, data, pin.neutral(model))
        column = {joint.index: k for k, joint in enumerate(robot.joints)}
        # Per joint (after the universe): parent, fixed rotation and offset in the parent (the
        # neutral placement for a joint that is not the robot's), and for the robot's joints
        # the column of its value, whether it turns, and its unit axis; for a turning joint,
        # the fixed rotation times the terms of Rodrigues' formula (see :meth:`centres`).
        self._steps: list[tuple[int, np.ndarray, np.ndarray, int, bool, np.ndarray]] = []
        for j in range(1, model.njoints):
            k = column.get(j, -1)
            fixed = model.jointPlacements[j] if k >= 0 else data.liMi[j]
            motion = np.asarray(data.joints[j].S, dtype=float).ravel()
            turning = k >= 0 and bool(np.any(motion[3:6]))
            axis = motion[3:6] if turning else motion[0:3]
            axis = axis / (np.linalg.norm(axis) or 1.0)
            rotation = fixed.rotation.copy()
            if turning:  # R_fixed (I + sin(a) K + (1 - cos(a)) K^2), K the axis' cross matrix
                skew = _skew(axis)
                rotation = np.stack([rotation, rotation @ skew, rotation @ skew @ skew])
            self._steps.append(
                (int(model.parents[j]), rotation, fixed.translation.copy(), k, turning, axis)
            )
        objects = list(geometry.geometryObjects)
        self._parents = np.array([int(obj.parentJoint) for obj in objects], dtype=int)
        self._local = np.array(
            [
                obj.placement.act(np.asarray(c, dtype=float))
                for obj, c in zip(objects, centres, strict=True)
            ]
        ).reshape(-1, 3)
        self._njoints = model.njoints
        #: The robot's joints (Pinocchio indices, in column order) and their unit axes.
        self._joints = np.array([joint.index for joint in robot.joints], dtype=int)
        self._axes = np.array([self._steps[j - 1][5] for j in self._joints]).reshape(-1, 3)
        self._last: tuple[tuple[tuple[int, ...], bytes], tuple[np.ndarray, np.ndarray]] | None
        self._last = None

    def centres(self, joints: np.ndarray) -> np.ndarray:
        """(B, G, 3) the sphere centres (m, spacecraft frame) at (B, N) joint values (rad or m)."""
        return self._centres(*self._forward(joints))

    def placed(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The sphere centres and the robot's joint axes at (B, N) joint values (rad or m).

        Returns (B, G, 3) the centres (m), (B, N, 3) each joint's origin (m) and (B, N, 3) its
        unit axis, in the spacecraft's frame (a revolute joint's origin lies on its axis).
        """
        rotations, offsets = self._forward(joints)
        axes = np.einsum("nbij,nj->bni", rotations[self._joints], self._axes)
        origins = offsets[self._joints].transpose(1, 0, 2)
        return self._centres(rotations, offsets), origins, axes

    def _forward(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every Pinocchio joint's rotation (J, B, 3, 3) and origin (J, B, 3; m) at the joints.

        The last batch's are kept: the collision model's sphere bounds and the lever arms
        (:mod:`freefloat.robot.pair_levers`) ask about the same joints in turn.
        """
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
        key = (joints.shape, joints.tobytes())
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        count = len(joints)
        rotations = np.empty((self._njoints, count, 3, 3))
        offsets = np.empty((self._njoints, count, 3))
        rotations[0], offsets[0] = np.eye(3), 0.0
        for j, (parent, fixed_r, fixed_t, k, turning, axis) in enumerate(self._steps, start=1):
            r_parent, t_parent = rotations[parent], offsets[parent]
            offsets[j] = t_parent + r_parent @ fixed_t
            if turning:
                angle = joints[:, k, None, None]
                local = fixed_r[0] + np.sin(angle) * fixed_r[1] + (1.0 - np.cos(angle)) * fixed_r[2]
                np.matmul(r_parent, local, out=rotations[j])
                continue
            rotation = r_parent @ fixed_r
            if k >= 0:  # a prismatic joint: along its axis, in its own (fixed) frame
                offsets[j] += (rotation @ axis) * joints[:, k, None]
            rotations[j] = rotation
        self._last = (key, (rotations, offsets))
        return rotations, offsets

    def _centres(self, rotations: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """(B, G, 3) the sphere centres (m) from :meth:`_forward`'s joint placements."""
        r, t = rotations[self._parents], offsets[self._parents]  # (G, B, 3, 3), (G, B, 3)
        world = np.einsum("gbij,gj->gbi", r, self._local) + t
        return world.transpose(1, 0, 2)

    def gaps(self, joints: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """(B, P) distances (m) between the sphere centres of each pair (P, 2; shape indices)."""
        return self.gaps_at(self.centres(joints), pairs)

    @staticmethod
    def gaps_at(centres: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """:meth:`gaps` from the (B, G, 3) centres (m)."""
        return np.linalg.norm(centres[:, pairs[:, 0]] - centres[:, pairs[:, 1]], axis=2)


def _skew(axis: np.ndarray) -> np.ndarray:
    """The cross-product matrix of ``axis``: ``_skew(a) @ v == a x v``."""
    return np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
